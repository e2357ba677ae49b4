"""Expansion of batch INPUTS into one work item per clip."""

from __future__ import annotations

import numpy as np
import pytest

from motion2robot.batch.work import WorkItem, count_clips, expand_inputs
from motion2robot.errors import UserError
from tests._shared import MOTIONS, requires_shared


def _clip(frames: int = 30, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.normal(size=(frames, 22, 3)).astype(np.float32)


def test_key_is_path_and_clip():
    assert WorkItem("/a/b.npy", 3).key == "/a/b.npy#3"
    assert WorkItem("/a/b.npy", None).key == "/a/b.npy#*"


def test_folder_recursive_sorted_and_filtered(tmp_path):
    (tmp_path / "sub" / "deeper").mkdir(parents=True)
    np.save(tmp_path / "b.npy", _clip())
    np.save(tmp_path / "sub" / "a.npy", _clip())
    np.save(tmp_path / "sub" / "deeper" / "c.npy", _clip())
    (tmp_path / "notes.md").write_text("not a motion")
    np.save(tmp_path / "Mean.npy", np.zeros(263))  # feature statistics: skipped, not an error
    exp = expand_inputs([tmp_path])
    names = [i.path.removeprefix(str(tmp_path.resolve())) for i in exp.items]
    assert names == ["/b.npy", "/sub/a.npy", "/sub/deeper/c.npy"]
    assert all(i.clip == 0 for i in exp.items)
    assert [p.endswith("Mean.npy") for p, _ in exp.skipped] == [True]
    assert exp.count_errors == {}


def test_explicit_1d_file_is_kept_so_the_reader_explains(tmp_path):
    np.save(tmp_path / "Std.npy", np.ones(263))
    exp = expand_inputs([tmp_path / "Std.npy"])
    assert [i.clip for i in exp.items] == [0] and not exp.skipped


def test_multi_clip_batches_expand_per_clip(tmp_path):
    np.save(tmp_path / "batch.npy", np.stack([_clip(), _clip(seed=1), _clip(seed=2)]))  # (N, T, 22, 3)
    np.save(tmp_path / "mdm_layout.npy", np.zeros((4, 22, 3, 20), np.float32))  # (N, 22, 3, T)
    np.save(tmp_path / "feats.npy", np.zeros((2, 20, 263), np.float32))  # (N, T, 263)
    np.save(tmp_path / "one_feat.npy", np.zeros((20, 263), np.float32))
    exp = expand_inputs([tmp_path])
    counts = {}
    for i in exp.items:
        counts.setdefault(i.path.rsplit("/", 1)[1], []).append(i.clip)
    assert counts == {"batch.npy": [0, 1, 2], "feats.npy": [0, 1], "mdm_layout.npy": [0, 1, 2, 3],
                      "one_feat.npy": [0]}


def test_npz_counts_its_joints_array(tmp_path):
    np.savez(tmp_path / "two.npz", joints=np.stack([_clip(), _clip()]), fps=30.0)
    assert count_clips(tmp_path / "two.npz") == 2


def test_manifest_relative_paths_comments_and_dedup(tmp_path):
    (tmp_path / "data").mkdir()
    np.save(tmp_path / "data" / "x.npy", _clip())
    np.save(tmp_path / "data" / "y.npy", _clip())
    man = tmp_path / "list.txt"
    man.write_text("# a comment\n\ndata/x.npy\ndata/x.npy\n  data/y.npy  \ndata/missing.npy\n")
    exp = expand_inputs([man, tmp_path / "data" / "y.npy"])
    assert [i.path.rsplit("/", 1)[1] for i in exp.items] == ["x.npy", "y.npy", "missing.npy"]
    missing = exp.items[-1]
    assert missing.clip is None and "missing.npy" in exp.count_errors[missing.path]


def test_manifest_loop_and_missing_input_are_user_errors(tmp_path):
    man = tmp_path / "self.lst"
    man.write_text("self.lst\n")
    with pytest.raises(UserError, match="lists itself"):
        expand_inputs([man])
    with pytest.raises(UserError, match="no such file"):
        expand_inputs([tmp_path / "nope.npy"])
    with pytest.raises(UserError, match="no INPUTS"):
        expand_inputs([])


def test_corrupt_file_becomes_an_uncountable_item(tmp_path):
    (tmp_path / "broken.npy").write_bytes(b"\x93NUMPY garbage")
    exp = expand_inputs([tmp_path])
    (item,) = exp.items
    assert item.clip is None and item.key.endswith("broken.npy#*")
    assert exp.count_errors[item.path]


@requires_shared
def test_shared_motions_expand_with_mdm_results_per_sample():
    exp = expand_inputs([MOTIONS])
    per_file: dict[str, int] = {}
    for i in exp.items:
        per_file[i.path] = per_file.get(i.path, 0) + 1
    assert per_file[str((MOTIONS / "mdm_results" / "mdm_throw_ball_results.npy").resolve())] == 30
    assert per_file[str((MOTIONS / "mdm_results" / "mdm_walk_pickup_results.npy").resolve())] == 3
    assert per_file[str((MOTIONS / "bvh" / "cmu_01_01.bvh").resolve())] == 1
    assert sorted(p.rsplit("/", 1)[1] for p, _ in exp.skipped) == ["Mean.npy", "Std.npy"]
    assert len({i.key for i in exp.items}) == len(exp.items)
