"""The opt-in MuJoCo bench (scripts/bench-mujoco) reads its rig — every number of our physics
bench's scene — from the repository's sources. It runs only on request, so a move of those
sources would break it silently (it did once, when SimWorld was split by job); this reads the
rig without MuJoCo, on every test run."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_mujoco  # noqa: E402


def test_the_mujoco_bench_reads_its_rig_from_our_sources():
    rig = bench_mujoco.read_rig(list(bench_mujoco.ARMS))
    assert rig.dt == 0.002 and rig.substeps == 25
    assert set(rig.arms) == set(bench_mujoco.ARMS)
    assert 0.0 < rig.finger_open < 0.05
    assert len(rig.arena) >= 2, "the pick-place bins' parts"
