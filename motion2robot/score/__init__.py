"""Score sets of generated samples for a robot: ``motion2robot score`` and :mod:`motion2robot.api`.

Built on ``batch``: every sample is a batch row (read -> retarget with the tempo/legs policy ->
check -> :mod:`~motion2robot.score.fidelity`), each set's rows in its own resumable results file
(:mod:`~motion2robot.score.sets`), the figures of a set computed from its rows
(:mod:`~motion2robot.score.figures`, ``batch-report``'s summary plus tempo, fallback, fidelity and
throughput) and shown as a table (:mod:`~motion2robot.score.table`) and an HTML page
(:mod:`~motion2robot.score.report_html`).
"""

from motion2robot.score.figures import SetFigures, set_figures
from motion2robot.score.fidelity import fidelity

__all__ = ["SetFigures", "fidelity", "set_figures"]
