"""Edit pairs: a source motion and its edit retargeted so that what the edit did not change stays."""

from motion2robot.edit.pair import EditResult, retarget_edit

__all__ = ["EditResult", "retarget_edit"]
