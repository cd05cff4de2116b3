"""A received wrench into the identifiers' input: tare removed, rotated into world, shifted by the known delay."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core.tare import Tare
from bsp_ros.live.online.frames import rotation_from_quaternion_xyzw
from bsp_ros.live.online.wrench_input import WrenchInput
from msg_adapters.wrench import WrenchSample

G_WORLD = np.array([0.0, 0.0, -9.81])
# A sensor turned 30 degrees about x then 20 about y: every axis mixes.
ROTATION = rotation_from_quaternion_xyzw([0.2549, 0.1677, 0.0449, 0.9513])
FORCE_WORLD, MOMENT_WORLD = np.array([1.0, -2.0, 3.0]), np.array([0.4, -0.5, 0.6])


def _separated_tare(frame_id: str = "ft_sensor") -> tuple[Tare, np.ndarray, np.ndarray]:
    """A tare with offsets and a handle of 0.3 kg whose centre of mass is off the sensor's origin, and what the
    sensor reads with the handle alone at ``ROTATION`` (the tare model's own formula, docs)."""
    offset_force, mass, offset_moment, first_moment = (
        np.array([0.5, -0.2, 1.0]),
        0.3,
        np.array([0.05, 0.0, -0.02]),
        0.3 * np.array([0.0, 0.02, 0.05]),
    )
    values = np.concatenate((offset_force, [mass], offset_moment, first_moment))
    tare = Tare(
        frame_id=frame_id,
        load="separated",
        values=values,
        covariance=np.zeros((10, 10)),
        n_samples=100,
        start_time_ns=0,
        duration_s=10.0,
    )
    gravity_sensor = ROTATION.T @ G_WORLD
    return tare, offset_force + mass * gravity_sensor, offset_moment + np.cross(first_moment, gravity_sensor)


def test_the_hands_wrench_comes_out_in_world_without_the_handle_and_on_the_angles_clock() -> None:
    tare, handle_force, handle_moment = _separated_tare()
    reading = WrenchSample(
        1_000_000_000, "ft_sensor", ROTATION.T @ FORCE_WORLD + handle_force, ROTATION.T @ MOMENT_WORLD + handle_moment
    )
    world = WrenchInput(tare, delay_s=0.005).world(reading, ROTATION)
    assert world is not None
    t_ns, wrench_yzx = world
    assert t_ns == 995_000_000  # measured 5 ms before its stamp
    assert wrench_yzx == pytest.approx([FORCE_WORLD[1], FORCE_WORLD[2], MOMENT_WORLD[0]], abs=1e-12)


def test_without_a_tare_only_the_rotation_applies_and_a_wrench_of_another_frame_is_left_out() -> None:
    reading = WrenchSample(7, "ft_sensor", ROTATION.T @ FORCE_WORLD, ROTATION.T @ MOMENT_WORLD)
    world = WrenchInput().world(reading, ROTATION)
    assert world is not None and world[0] == 7
    assert world[1] == pytest.approx([FORCE_WORLD[1], FORCE_WORLD[2], MOMENT_WORLD[0]], abs=1e-12)
    tare, _, _ = _separated_tare("another_sensor")
    assert WrenchInput(tare).world(reading, ROTATION) is None
