"""Two-speed protocols: the same angles slow, then fast; `bsp plan --speeds` writes one and refuses what it cannot."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bsp_ros.cli import main
from bsp_ros.core.identification.joint.speed_split import SpeedGroups, speed_groups
from bsp_ros.core.planning import planned_trajectory_from_file, trajectory_from_points
from bsp_ros.core.planning.trajectory import PlannedTrajectory
from bsp_ros.core.planning.two_speed import TwoSpeedPath, fast_repeats, two_speed_trajectory
from bsp_ros.core.simulation import human_arm_cell

LIMITS = ["--shoulder", "0", "1.2", "--shoulder-range", "-70", "-10", "--elbow-range", "10", "100"]
RATE_HZ = 100.0


def groups_of(
    trajectory: PlannedTrajectory | TwoSpeedPath, duration_s: float, joint: int
) -> tuple[SpeedGroups | None, np.ndarray, np.ndarray]:
    """:func:`speed_groups` of one joint of ``trajectory`` sampled at 100 Hz (its velocity standing in for the
    direction-of-motion velocity), with the samples' times and angles."""
    t_s = np.arange(0.0, duration_s, 1.0 / RATE_HZ)
    q, v = trajectory.angles_rad(t_s)[:, joint], trajectory.velocities_rad_s(t_s)[:, joint]
    v = np.where(np.abs(v) > 1e-6, v, 0.0)
    return speed_groups(np.round(t_s * 1e9).astype(np.int64), q, v), t_s, q


def test_a_planned_motion_is_played_slow_then_fast_over_the_same_angles() -> None:
    centres = np.radians([[-40.0, 50.0, 0.0]])
    base = trajectory_from_points(centres, np.radians([10.0, 12.0, 8.0]), 20.0, 0.12)
    ratio = 4.0
    trajectory = two_speed_trajectory(base, ratio)
    assert trajectory.duration_s == pytest.approx(base.duration_s * (ratio + fast_repeats(ratio)))
    slow_s = base.duration_s * ratio
    t_s = trajectory.dense_times_s()
    speed = np.abs(trajectory.velocities_rad_s(t_s)).max(axis=1)
    assert speed[t_s < slow_s].max() == pytest.approx(max(base.peak_speed_rad_s) / ratio, rel=1e-6)
    assert speed[t_s > slow_s].max() == pytest.approx(max(base.peak_speed_rad_s), rel=1e-6)
    for j in range(3):
        found, times, q = groups_of(trajectory, trajectory.duration_s, j)
        assert found is not None, j
        assert found.fast_rad_s / found.slow_rad_s == pytest.approx(ratio, rel=0.05)
        assert not found.fast[times < slow_s - 1].any() and found.fast[times > slow_s + 1].mean() > 0.9
        slow, fast = q[times < slow_s], q[times > slow_s]
        assert slow.min() == pytest.approx(fast.min(), abs=1e-9) and slow.max() == pytest.approx(fast.max(), abs=1e-9)


def test_the_two_speed_path_is_the_base_motion_time_warped_smoothly() -> None:
    base = human_arm_cell().trajectory
    path = TwoSpeedPath(base, (1.0, 4.0), 30.0, 60.0)
    t_s = np.linspace(0.5, 59.5, 2000)
    step = 1e-4
    numeric_v = (path.angles_rad(t_s + step) - path.angles_rad(t_s - step)) / (2 * step)
    numeric_a = (path.velocities_rad_s(t_s + step) - path.velocities_rad_s(t_s - step)) / (2 * step)
    assert np.abs(path.velocities_rad_s(t_s) - numeric_v).max() < 1e-8
    assert np.abs(path.accelerations_rad_s2(t_s) - numeric_a).max() < 1e-6
    early, late = t_s < 29.0, t_s > 31.0
    np.testing.assert_allclose(path.angles_rad(t_s[early]), base.angles_rad(t_s[early]))
    shoulder = path.velocities_rad_s(t_s)[:, 0]
    assert np.abs(shoulder[late]).max() == pytest.approx(4 * np.abs(shoulder[early]).max(), rel=0.02)


def test_bsp_plan_speeds_writes_a_two_speed_plan(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "two_speed.json"
    args = [*LIMITS, "--wrist-range", "-20", "20", "--operating-points", "1", "--max-evaluations", "40"]
    assert main(["plan", *args, "--max-speed", "0.12", "--speeds", "0.03", "0.12", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "two speeds: 60 s at 0.03 rad/s, then 60 s at 0.12 rad/s" in printed
    assert "static_moment_kgm/upper_arm" in printed  # the predicted stds still come out
    trajectory = planned_trajectory_from_file(out)
    assert trajectory.duration_s == pytest.approx(120.0)
    for j in range(3):
        found, _, _ = groups_of(trajectory, trajectory.duration_s, j)
        assert found is not None
        assert found.slow_rad_s < 0.03 and found.fast_rad_s < 0.12
        assert found.fast_rad_s / found.slow_rad_s == pytest.approx(4.0, rel=0.05)


@pytest.mark.parametrize(
    ("speeds", "message"),
    [
        (["0.03", "0.2"], "exceeds the speed limit 0.12 rad/s"),
        (["0.1", "0.12"], "must be 2 to 8 times the slow one"),
        (["0.01", "0.12"], "must be 2 to 8 times the slow one"),
    ],
)
def test_speeds_it_cannot_honour_are_refused_naming_them(
    speeds: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    args = [*LIMITS, "--wrist-range", "-20", "20", "--max-speed", "0.12", "--speeds", *speeds]
    assert main(["plan", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("bsp plan: error: ") and message in err[0]
