"""`bsp_identifier`'s parameters (the table it declares) and its settings parsed from their values, without rclpy."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.methods import LiveMode, Method
from bsp_ros.core.pipeline import IdentifyOptions
from bsp_ros.core.sensor_zero import ZERO_SD_N, ZERO_SD_NM
from bsp_ros.core.streams import segments_for
from bsp_ros.core.tare import Tare, read_tare_file
from bsp_ros.errors import BspError, InputError
from bsp_ros.live.online.frames import FrameSource, frame_source, rotation_from_quaternion_xyzw
from bsp_ros.live.online.precision import PrecisionTarget
from bsp_ros.live.online.precision_targets import precision_target_from_parameters
from bsp_ros.live.runtime.cell_parameters import CELL_FILE
from bsp_ros.live.runtime.parameters import Param

__all__ = ["MODES", "NAME", "PARAMETERS", "IdentifierSettings"]

NAME = "bsp_identifier"
MODES = tuple(m.value for m in LiveMode)

PARAMETERS = (
    CELL_FILE,
    Param(
        name="mode",
        default="windowed",
        description="windowed (sliding window) or recursive (per sample)",
        choices=MODES,
    ),
    Param(name="n_segments", default=3, description="2 (mechanical arm) or 3 (human arm)", lo=2, hi=3),
    Param(name="window_s", default=30.0, description="sliding window length", unit="s", lo=1.0, hi=3600.0),
    Param(name="update_hz", default=5.0, description="estimate rate", unit="Hz", lo=0.1, hi=100.0),
    Param(
        name="stale_s",
        default=0.4,
        description="an input silent this long makes the estimate invalid",
        unit="s",
        lo=0.01,
        hi=60.0,
    ),
    Param(
        name="method",
        default="joint",
        description="joint (ours) or paper (the method paper's sequential procedure)",
        choices=("joint", "paper"),
    ),
    Param(name="passive", default="coulomb", description="passive model, e.g. coulomb+viscous"),
    Param(
        name="body_mass_kg",
        default=0.0,
        description="subject body mass for the prior (0: unknown)",
        unit="kg",
        lo=0.0,
        hi=300.0,
    ),
    Param(name="height_m", default=0.0, description="subject height (0: unknown)", unit="m", lo=0.0, hi=2.5),
    Param(name="sex", default="male", description="anthropometric table", choices=("male", "female")),
    Param(name="world_frame", default="world", description="frame of the markers and of gravity (z up)"),
    Param(name="wrench_topic", default="/ft_sensor/wrench", description="WrenchStamped topic"),
    Param(
        name="emg_topic",
        default="/emg/envelope",
        description="EMG envelopes (std_msgs/Float32MultiArray, channel names in layout.dim[0].label; '': not "
        "subscribed): the stretches they show active are left out of the window as `bsp identify` leaves them out; "
        "each message is stamped at its receipt, on the wrench stamps' clock",
    ),
    Param(
        name="wrench_frame_source",
        default="auto",
        description="where the wrench frame's rotation comes from: tf (/tf_static and /tf), topic (TransformStamped of "
        "the wrench frame in world on wrench_frame_topic, e.g. the robot's flange: a sensor that turns without "
        "tf2_msgs), parameter (wrench_frame_rotation_xyzw), or auto (tf if tf2_msgs is installed, else the topic); "
        "where tf or the topic sends nothing within tf_wait_s, wrench_frame_rotation_xyzw stands in",
        choices=("auto", "tf", "topic", "parameter"),
    ),
    Param(
        name="wrench_frame_topic",
        default="ft_sensor/transform",
        description="geometry_msgs/TransformStamped topic of the wrench frame in world (wrench_frame_source topic)",
    ),
    Param(
        name="wrench_frame_rotation_xyzw",
        default=[0.0, 0.0, 0.0, 1.0],
        description="rotation world <- wrench frame as a unit quaternion [x, y, z, w] (default: the cell file's "
        "mounting), used without a transform; a transform more than 1 deg off it is reported",
    ),
    Param(
        name="tare_file",
        default="",
        description="a `bsp tare` file (bsp_ros/core/tare/1) of this sensor: its offset and handle load are removed "
        "from every wrench and its uncertainty joins the windowed estimate's ('': none, and the estimate says so)",
    ),
    Param(
        name="zero_sd_n",
        default=ZERO_SD_N,
        description="without a tare, how far (1 sd per sensor axis) the sensor's force zero may be off: the data "
        "cannot tell a force offset from arm weight, so it is in the std (`bsp identify --zero-sd-n`)",
        unit="N",
        lo=0.0,
        hi=100.0,
    ),
    Param(
        name="zero_sd_nm",
        default=ZERO_SD_NM,
        description="the same for the sensor's moment zero",
        unit="N m",
        lo=0.0,
        hi=10.0,
    ),
    Param(
        name="support_fraction",
        default=0.0,
        description="share of the identified arm's gravity torques the robot should carry (bsp/weight_support, "
        "published at the joint-state rate while the estimate is valid; 0: not published)",
        lo=0.0,
        hi=1.0,
    ),
    Param(
        name="wrench_delay_s",
        default=None,
        description="delay of the wrench stamps behind the joint-state (marker) stamps the cell knows: a wrench "
        "stamped t was measured at t - wrench_delay_s; its stamps are shifted back by it, as `bsp identify "
        "--wrench-delay-s` does (unset: `bsp identify` estimates it, which live updates cannot: live applies 0 and "
        "says so)",
        unit="s",
        lo=-10.0,
        hi=10.0,
        kind=float,
    ),
    Param(
        name="tf_wait_s",
        default=2.0,
        description="wait this long for the wrench frame's transform before taking wrench_frame_rotation_xyzw",
        unit="s",
        lo=0.0,
        hi=60.0,
    ),
    Param(
        name="target_std_percent",
        default=0.0,
        description="the session is precise enough once the static moment of every segment of target_segments has a "
        "relative std at or below this in valid estimates for precision_hold_s: bsp/precision_reached (latched Bool) "
        "turns true for the rest of the session, the estimate JSON says so under `precision` (0: off, nothing "
        "published)",
        unit="%",
        lo=0.0,
        hi=100.0,
    ),
    Param(
        name="precision_hold_s",
        default=5.0,
        description="how long every targeted std must stay within target_std_percent before the signal comes",
        unit="s",
        lo=0.0,
        hi=600.0,
    ),
    Param(
        name="target_segments",
        default=["upper_arm", "forearm"],
        description="the segments whose static moment target_std_percent is for (the hand's short lever leaves its "
        "static moment 15-40 % uncertain from skin markers: add it where the robot gives the contact point)",
    ),
    Param(
        name="target_parameters",
        default="",
        description="the parameters target_std_percent is for instead, owner.quantity joined by commas, e.g. "
        "forearm.static_moment_kgm,elbow.coulomb_nm (a joint's: its passive model's; empty: target_segments)",
    ),
    Param(
        name="plan_file",
        default="",
        description="a `bsp plan --json` file: the session is precise enough once each static moment has the "
        "relative std the plan predicts (target_std_percent then 0; window_s at least the plan's duration)",
    ),
)

_BY_NAME = {p.name: p for p in PARAMETERS}


def _checked(param: Param, value: Any) -> Any:
    """``value`` of ``param`` as rclpy's descriptor would take it (type, range, finiteness, choices).

    Raises
    ------
    InputError
        Naming the parameter and the value.
    """
    where = f"{NAME}: parameter {param.name!r}"
    if value is None:
        if param.default is None:
            return None
        raise InputError(f"{where} needs a value")
    kind = param.value_type
    if kind in (int, float):
        if isinstance(value, bool) or not isinstance(value, int | float) or (kind is int and isinstance(value, float)):
            raise InputError(f"{where} must be {'an integer' if kind is int else 'a number'}, got {value!r}")
        value = kind(value)
        if not math.isfinite(value):
            raise InputError(f"{where} must be finite, got {value!r}")
        if (param.lo is not None and value < param.lo) or (param.hi is not None and value > param.hi):
            raise InputError(f"{where} must be within {param.lo:g} .. {param.hi:g}, got {value!r}")
    elif kind is list:
        value = list(value)
    elif not isinstance(value, kind):
        raise InputError(f"{where} must be a {kind.__name__}, got {value!r}")
    if param.choices and value not in param.choices:
        raise InputError(f"{where} must be one of {param.choices}, got {value!r}")
    return value


@dataclass(frozen=True, kw_only=True)
class IdentifierSettings:
    """`bsp_identifier`'s settings, parsed and checked once at start (:meth:`from_parameters`).

    Attributes
    ----------
    mode : the sliding window or the per-sample filter.
    n_segments : 2 or 3.
    window_s, update_hz, stale_s, tf_wait_s : as the parameters (s, Hz).
    options : what each estimate is identified with (method, passive model, subject, tare, sensor zero's sd, the
        wrench delay): the passive model as named (no elastic fallback per update).
    world_frame, wrench_topic, wrench_frame_source, wrench_frame_topic : as the parameters.
    emg_topic : the EMG envelopes' topic ('' none).
    wrench_frame_rotation_xyzw : the parameter quaternion; ``wrench_frame_rotation`` its (3, 3) matrix.
    tare_file : the tare's path ('' without one; the tare itself is ``options.tare``).
    support_fraction : the weight support's share (0: not published).
    wrench_delay_s : the wrench delay the cell knows (s), or None when unset (live applies 0:
        :attr:`live_wrench_delay_s`).
    target_std_percent, precision_hold_s, target_segments : the precision signal's target (%, 0: off), hold (s) and
        the segments whose static moments it is for.
    precision_target : what the session is for (the parameters above, ``target_parameters`` or ``plan_file``:
        :func:`bsp_ros.live.online.precision_targets.precision_target_from_parameters`), or None when off.
    """

    mode: LiveMode
    n_segments: int
    window_s: float
    update_hz: float
    stale_s: float
    options: IdentifyOptions
    world_frame: str
    wrench_topic: str
    wrench_frame_source: str
    wrench_frame_topic: str
    wrench_frame_rotation_xyzw: tuple[float, ...]
    wrench_frame_rotation: np.ndarray = field(compare=False, repr=False)
    tare_file: str
    support_fraction: float
    wrench_delay_s: float | None
    tf_wait_s: float
    target_std_percent: float = 0.0
    precision_hold_s: float = 5.0
    target_segments: tuple[str, ...] = ("upper_arm", "forearm")
    emg_topic: str = ""
    precision_target: PrecisionTarget | None = None

    @classmethod
    def from_parameters(cls, values: Mapping[str, Any]) -> IdentifierSettings:
        """The settings from parameter values (``declare_parameters``' result, or any mapping: a missing name takes
        its default); the tare file is read here.

        Raises
        ------
        InputError
            An unknown name or a value the parameter does not take (the message names the parameter).
        """
        unknown = sorted(set(values) - set(_BY_NAME))
        if unknown:
            raise InputError(f"{NAME}: unknown parameter(s) {', '.join(unknown)}")
        p = {name: _checked(param, values.get(name, param.default)) for name, param in _BY_NAME.items()}
        try:
            rotation = rotation_from_quaternion_xyzw(p["wrench_frame_rotation_xyzw"])
        except ValueError as exc:
            raise InputError(f"{NAME}: parameter wrench_frame_rotation_xyzw: {exc}") from exc
        # The model named by the parameter, kept: a window showing an elastic moment it lacks is invalid with the
        # warning (choosing among the elastic family per 5 Hz update is `bsp identify --passive auto`'s work).
        options = IdentifyOptions(
            method=Method(p["method"]),
            passive=_passive(p["passive"]),
            subject=SubjectInfo(p["body_mass_kg"] or None, p["height_m"] or None, p["sex"]),
            tare=_tare(p["tare_file"]),
            wrench_delay_s=p["wrench_delay_s"],
            elastic_fallback=False,
            zero_sd_n=p["zero_sd_n"],
            zero_sd_nm=p["zero_sd_nm"],
        )
        segments = _target_segments(p["target_segments"], p["n_segments"])
        return cls(
            mode=LiveMode(p["mode"]),
            n_segments=p["n_segments"],
            window_s=p["window_s"],
            update_hz=p["update_hz"],
            stale_s=p["stale_s"],
            options=options,
            world_frame=p["world_frame"],
            wrench_topic=p["wrench_topic"],
            wrench_frame_source=p["wrench_frame_source"],
            wrench_frame_topic=p["wrench_frame_topic"],
            wrench_frame_rotation_xyzw=tuple(float(v) for v in p["wrench_frame_rotation_xyzw"]),
            wrench_frame_rotation=rotation,
            tare_file=p["tare_file"],
            support_fraction=float(p["support_fraction"]),
            wrench_delay_s=p["wrench_delay_s"],
            tf_wait_s=p["tf_wait_s"],
            target_std_percent=p["target_std_percent"],
            precision_hold_s=p["precision_hold_s"],
            target_segments=segments,
            emg_topic=p["emg_topic"],
            precision_target=precision_target_from_parameters(
                p, segments, options.passive, p["window_s"] if p["mode"] == LiveMode.WINDOWED else None
            ),
        )

    @property
    def live_wrench_delay_s(self) -> float:
        """The delay the live path applies to each wrench, s: the parameter's, 0 when unset."""
        return 0.0 if self.wrench_delay_s is None else self.wrench_delay_s

    @property
    def wrench_delay_note(self) -> str:
        """What the node does with the wrench delay, for its log and /diagnostics."""
        if self.wrench_delay_s is None:
            return (
                "unset: 0 s applied (a live update cannot estimate it as `bsp identify` does; "
                "set wrench_delay_s if the cell knows it)"
            )
        return f"{self.wrench_delay_s:g} s (parameter wrench_delay_s, compensated)"

    def frame_source(self, tf_installed: bool) -> FrameSource:
        """Where the wrench frame's rotation comes from (``tf_installed``: tf2_msgs is there).

        Raises
        ------
        InputError
            ``wrench_frame_source`` is tf without tf2_msgs.
        """
        try:
            return frame_source(self.wrench_frame_source, tf_installed, self.wrench_frame_topic)
        except ValueError as exc:
            raise InputError(f"{NAME}: {exc}") from exc


def _target_segments(names: list[Any], n_segments: int) -> tuple[str, ...]:
    """The segments of ``target_segments``, each one of the chain's, at least one."""
    chain = segments_for(n_segments)
    segments = tuple(str(name) for name in names)
    unknown = [name for name in segments if name not in chain]
    if unknown or not segments:
        raise InputError(
            f"{NAME}: parameter target_segments must name segments of the {n_segments}-segment chain "
            f"({', '.join(chain)}), got {list(segments)!r}"
        )
    return segments


def _passive(label: str) -> PassiveModel:
    try:
        return PassiveModel.parse(label)
    except (BspError, ValueError) as exc:
        raise InputError(f"{NAME}: parameter passive: {exc}") from exc


def _tare(path: str) -> Tare | None:
    if not path:
        return None
    try:
        return read_tare_file(path)
    except BspError as exc:
        raise InputError(f"{NAME}: parameter tare_file {path}: {exc}") from exc
