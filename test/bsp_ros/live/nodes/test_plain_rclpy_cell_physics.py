"""The plain-rclpy cell's wrench (its own rigid-body dynamics) against pinocchio's recursive Newton-Euler."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from pinocchio_chain import planar_chain

pin = pytest.importorskip("pinocchio", reason="pinocchio (pip 'pin') is the independent rigid-body oracle")
pytest.importorskip("rclpy", reason="the cell is an rclpy script (the live extra)")


def _cell():
    spec = importlib.util.spec_from_file_location("plain_rclpy_cell", Path(__file__).with_name("plain_rclpy_cell.py"))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_cell_s_wrench_balances_pinocchio_s_inverse_dynamics_along_its_path() -> None:
    cell = _cell()
    chain = planar_chain(
        pin, cell.LENGTHS_M, cell.MASSES_KG, cell.COM_M, np.zeros(3), cell.INERTIA_COM_KGM2, cell.SHOULDER_M, cell.G
    )
    data = chain.createData()
    inertial_share = []
    for t_s in np.linspace(0.0, 40.0, 61):
        q, qd, qdd = cell.motion(float(t_s))
        torque = pin.rnea(chain, data, q, qd, qdd)
        # The contact point's Jacobian (y, z, angle) maps the wrench on the sensor to joint torques: the sensor
        # pushes the hand with -w, which the joints' torques (none: a relaxed arm) and gravity balance.
        phi = np.cumsum(q)
        jac = np.array(
            [
                [-np.sum(cell.LENGTHS_M[j:] * np.sin(phi[j:])) for j in range(3)],
                [np.sum(cell.LENGTHS_M[j:] * np.cos(phi[j:])) for j in range(3)],
                [1.0, 1.0, 1.0],
            ]
        )
        np.testing.assert_allclose(-jac.T @ cell.wrench_yzx(q, qd, qdd), torque, atol=1e-10)
        gravity = pin.computeGeneralizedGravity(chain, data, q)
        inertial_share.append(np.abs(torque - gravity) / np.abs(gravity).max())
    # The path is dynamic enough that a quasi-static wrench would be wrong by more than the sensor noise.
    assert np.max(inertial_share) > 0.005
