"""Plan files: JSON and CSV carry the trajectory exactly, the loader re-checks limits and refuses foreign files."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bsp_ros.core.planning import (
    PLAN_SCHEMA,
    Plan,
    handle_poses_world,
    planned_trajectory_from_file,
    write_plan_csv,
    write_plan_json,
)
from bsp_ros.core.planning.files import csv_columns
from bsp_ros.errors import InputError


def test_json_plan_loads_back_exactly(plan: Plan, tmp_path) -> None:
    loaded = planned_trajectory_from_file(write_plan_json(tmp_path / "plan.json", plan))
    t = np.linspace(0.0, 120.0, 997)
    np.testing.assert_array_equal(loaded.angles_rad(t), plan.trajectory.angles_rad(t))


def test_json_holds_handle_poses_consistent_with_the_joint_angles(plan: Plan, tmp_path) -> None:
    data = json.loads(write_plan_json(tmp_path / "plan.json", plan, rate_hz=5.0).read_text())
    assert data["schema"] == PLAN_SCHEMA
    samples = data["samples"]
    poses = handle_poses_world(samples["q_rad"], data["lengths_m"], data["shoulder_yz_m"])
    np.testing.assert_allclose(poses[:, 0], samples["handle_y_m"], atol=1e-12)
    np.testing.assert_allclose(poses[:, 2], samples["handle_pitch_rad"], atol=1e-12)
    assert len(samples["t_s"]) == 601
    assert {row["quantity"] for row in data["predicted"]} >= {"static_moment_kgm", "offset_nm"}


def test_csv_plan_loads_back_within_a_microradian(plan: Plan, tmp_path) -> None:
    path = write_plan_csv(tmp_path / "plan.csv", plan, rate_hz=10.0)
    assert path.read_text().splitlines()[0].split(",") == csv_columns(3)
    loaded = planned_trajectory_from_file(path)
    t = np.linspace(0.0, 120.0, 997)
    np.testing.assert_allclose(loaded.angles_rad(t), plan.trajectory.angles_rad(t), atol=1e-6)


def test_a_tampered_plan_beyond_its_limits_is_refused(plan: Plan, tmp_path) -> None:
    path = write_plan_json(tmp_path / "plan.json", plan)
    data = json.loads(path.read_text())
    data["limits"]["range_deg"]["wrist"]["high_deg"] = 1.0
    path.write_text(json.dumps(data))
    with pytest.raises(InputError, match=r"wrist reaches .* above its limit 1 deg"):
        planned_trajectory_from_file(path)


@pytest.mark.parametrize(
    ("name", "text", "needle"),
    [
        ("foreign.json", '{"schema": "bsp_ros/core/estimate/1"}', "not a bsp_ros/plan/1"),
        ("broken.json", "{", "not valid JSON"),
        ("bad.csv", "a,b\n1,2\n", "CSV columns"),
        ("missing.json", None, "does not exist"),
    ],
)
def test_bad_plan_files_are_refused(tmp_path, name, text, needle) -> None:
    path = tmp_path / name
    if text is not None:
        path.write_text(text)
    with pytest.raises(InputError, match=needle):
        planned_trajectory_from_file(path)
