"""The Python API for notebooks and pipelines: identify bags, simulate sessions, open the session store.

``import bsp_ros`` stays light: these functions load the estimator when first called. See docs/api.md.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

if TYPE_CHECKING:
    from bsp_ros.clinic.store import Store
    from bsp_ros.core.estimate_schema import Estimate

__all__ = ["identify", "open_store", "simulate", "to_frame", "to_records"]

PathLike = str | os.PathLike[str]


def identify(
    bag_or_bags: PathLike | Sequence[PathLike],
    *,
    method: str = "joint",
    passive: str | None = None,
    tare: PathLike | None = None,
    body_mass_kg: float | None = None,
    height_m: float | None = None,
    sex: str | None = None,
    trunk_tilt_deg: Sequence[float] | None = None,
    marker_placement_sd_mm: float = 2.0,
    handle_pose_sd_mm: float = 0.5,
    zero_sd_n: float | None = None,
    zero_sd_nm: float | None = None,
    wrench_delay_s: float | None = None,
    cell: PathLike | None = None,
    wrench_topic: str | None = None,
    marker_topics: Mapping[str, str] | None = None,
    tf_topic: str | None = None,
    tf_static_topic: str | None = None,
    handle_pose_topic: str | None = None,
    emg_topic: str | None = None,
) -> Estimate:
    """Identify one arm from a bag, or from several recordings of it (each with its trunk's tilt), as
    ``bsp identify`` does with the same options (each keyword is the option of that name: ``cell`` is ``--cell``,
    ``marker_topics`` the ``--marker-topic NAME=TOPIC`` remaps).

    Parameters
    ----------
    bag_or_bags : a rosbag2 MCAP bag directory or ``.mcap`` file, or several recordings of one arm (for many
        bags each its own session: ``bsp identify --each``, or call this once per bag).
    method : ``joint`` (stacked, with the model checks) or ``paper`` (the method paper's sequential fit).
    passive : the passive model (``coulomb``, ``coulomb+viscous``, ``auto``, ...); None: Coulomb, with the
        elastic family the data choose where they reject it.
    tare : a ``bsp tare`` file to subtract (its uncertainty joins the std); None: the cell file's, if any.
    body_mass_kg, height_m, sex : the subject's body data, for the anthropometric prior (kg, m; sex None: male).
    trunk_tilt_deg : one tilt per recording (deg), for recordings at several trunk postures.
    marker_placement_sd_mm : how far a skin marker may sit from its joint centre (1 sd per axis, mm).
    handle_pose_sd_mm : the robot's contact point's registration to world (1 sd per axis, mm).
    zero_sd_n, zero_sd_nm : without a tare, the sensor zero's assumed sd (N, N m); None: the CLI's defaults.
    wrench_delay_s : the wrench stamps' delay behind the markers' the cell knows (s); None: estimated.
    cell : a cell description file (``bsp_ros/cell/1``): its topics for those not given here, its tare without
        ``tare``, its sensor mounting where the bag records no rotation.
    wrench_topic, tf_topic, tf_static_topic : the topics' names (None: the cell's, else the contract's defaults).
    marker_topics : marker name -> topic, for the markers whose topics differ (e.g. ``{"elbow": "/vicon/elbow"}``).
    handle_pose_topic : the robot's contact point (``""``: use the hand marker); None: the default.
    emg_topic : the EMG envelopes (``""``: ignore them); None: the cell's, else ``/emg/envelope``.

    Returns
    -------
    Estimate
        Typed and frozen (``bsp_ros.core.estimate_schema``): ``to_json()`` gives the docs/contract.md document,
        :func:`to_records` a flat table.

    Raises
    ------
    bsp_ros.errors.BspError
        A bad option (``InputError``, naming the `bsp identify` option), or the bag cannot be read (a ``BagError``
        whose ``code`` names why, e.g. ``missing-topic``: `bsp identify` exits 10-16 by it) or gives no estimate at
        all; poor excitation is an estimate whose ``valid`` is False, with its findings.
    """
    from bsp_ros.bag.offline import estimate_bags
    from bsp_ros.cli.identify_options import options_from_args, topics_from_args, trunk_tilts_rad

    paths = [Path(bag_or_bags)] if isinstance(bag_or_bags, str | os.PathLike) else [Path(b) for b in bag_or_bags]
    given: dict[str, Any] = {
        "--method": method,
        "--passive": passive,
        "--tare": tare,
        "--body-mass": body_mass_kg,
        "--height": height_m,
        "--sex": sex,
        "--marker-placement-sd-mm": marker_placement_sd_mm,
        "--handle-pose-sd-mm": handle_pose_sd_mm,
        "--zero-sd-n": zero_sd_n,
        "--zero-sd-nm": zero_sd_nm,
        "--wrench-delay-s": wrench_delay_s,
        "--cell": cell,
        "--wrench-topic": wrench_topic,
        "--tf-topic": tf_topic,
        "--tf-static-topic": tf_static_topic,
        "--handle-pose-topic": handle_pose_topic,
        "--emg-topic": emg_topic,
    }
    argv = [f"{option}={_argument(value)}" for option, value in given.items() if value is not None]
    argv += [f"--marker-topic={name}={topic}" for name, topic in (marker_topics or {}).items()]
    if trunk_tilt_deg is not None:
        argv += ["--trunk-tilt-deg", *(_argument(tilt) for tilt in trunk_tilt_deg)]
    args = identify_arguments(argv)
    tilts = trunk_tilts_rad(args.trunk_tilt_deg, len(paths))
    return estimate_bags(paths, options_from_args(args), topics_from_args(args), None, tilts)


class _Parser(argparse.ArgumentParser):
    """`bsp identify`'s options, whose refusal is an InputError (the CLI's line, no exit)."""

    def error(self, message: str) -> NoReturn:
        from bsp_ros.errors import InputError

        raise InputError(f"bsp_ros.identify: {message} (the option of `bsp identify`)")


def identify_arguments(argv: Sequence[str]) -> argparse.Namespace:
    """``argv`` parsed as `bsp identify`'s options (no bags): the API builds its options as the CLI does, with
    its checks, defaults and the cell file's topics.

    Raises
    ------
    InputError
        A value the CLI refuses (out of range, not a choice).
    """
    from bsp_ros.cli.identify_options import add_identify_arguments, add_trunk_tilt_argument

    parser = _Parser(prog="bsp_ros.identify", add_help=False)
    add_identify_arguments(parser)
    add_trunk_tilt_argument(parser)
    return parser.parse_args(list(argv))


def _argument(value: Any) -> str:
    # A float as repr, so the option parses back to the same number; a path as given.
    return repr(float(value)) if isinstance(value, int | float) and not isinstance(value, bool) else os.fspath(value)


def simulate(
    out: PathLike,
    *,
    subject: str = "human",
    duration_s: float = 120.0,
    seed: int = 0,
    body_mass_kg: float | None = None,
    height_m: float | None = None,
    sex: str | None = None,
) -> Path:
    """Simulate a rehab cell session and write it as a bag with its ground truth (``truth.json`` beside it), as
    ``bsp simulate`` does with the same options (its other options: the CLI).

    Parameters
    ----------
    out : the bag directory to create (it must not exist; name it after the session, never after a person).
    subject : ``human`` (a 3-segment arm, de Leva's table means) or ``paper-arm`` (the method paper's
        2-segment mechanical arm).
    duration_s : length (s).
    seed : seed of every random draw.
    body_mass_kg, height_m, sex : the human subject's body data (kg, m, ``male``/``female``; default 75 kg, 1.78 m,
        male, as ``bsp simulate``).

    Returns
    -------
    Path
        The bag directory.
    """
    from bsp_ros.bag import write_session_bag
    from bsp_ros.core import simulation
    from bsp_ros.errors import InputError

    path = Path(out)
    if path.exists():
        raise InputError(f"{path} exists already: refusing to overwrite")
    body_given = any(v is not None for v in (body_mass_kg, height_m, sex))
    if subject == "human":
        spec = simulation.human_arm_cell(
            sex=sex or "male",
            body_mass_kg=75.0 if body_mass_kg is None else body_mass_kg,
            height_m=1.78 if height_m is None else height_m,
            duration_s=duration_s,
            seed=seed,
        )
    elif subject == "paper-arm" and not body_given:
        spec = simulation.paper_mechanical_arm_cell(duration_s=duration_s, seed=seed)
    else:
        raise InputError(f"subject must be 'human' or 'paper-arm' (the latter without body data), got {subject!r}")
    simulated = simulation.simulate_cell(spec)
    write_session_bag(path, simulated.session, simulated.truth.to_dict(), seed=seed, tf_static=spec.sensor.tf_static)
    return path


def open_store(location: PathLike | None = None, *, create: bool = True) -> Store:
    """The session store at ``location`` (a SQLite file or a PostgreSQL URL; None: ``BSP_STORE`` or the user's
    default), as ``bsp sessions`` opens it."""
    from bsp_ros.clinic.store import open_store as _open_store

    return _open_store(location, create=create)


def to_records(estimate: Estimate) -> list[dict[str, Any]]:
    """The estimate as flat rows, one per quantity: ``group``, ``owner``, ``quantity``, ``value``, ``std``,
    ``source``, ``valid``, and one ``budget/<term>`` column per uncertainty term where the quantity has a budget.
    Ready for ``pandas.DataFrame`` or a CSV writer."""
    rows = []
    for group, owners in (("segments", estimate.segments), ("joints", estimate.joints)):
        for owner, quantities in owners.items():
            for key, q in quantities.items():
                row: dict[str, Any] = {
                    "group": group,
                    "owner": owner,
                    "quantity": key,
                    "value": q.value,
                    "std": q.std,
                    "source": str(q.source),
                    "valid": estimate.valid,
                }
                row.update({f"budget/{term}": u for term, u in (q.budget or {}).items()})
                rows.append(row)
    return rows


def to_frame(estimate: Estimate | Sequence[Estimate], labels: Sequence[str] | None = None) -> Any:
    """:func:`to_records` of one estimate or several as a ``pandas.DataFrame`` (pandas is not a dependency of
    bsp_ros: install it to use this). ``labels`` name each estimate in a ``label`` column (default: its source).

    Raises
    ------
    ImportError
        pandas is not installed.
    """
    try:
        import pandas as pd
    except ImportError as error:  # pragma: no cover - depends on the environment
        raise ImportError("to_frame needs pandas (pip install pandas); to_records needs nothing") from error
    estimates = [estimate] if not isinstance(estimate, Sequence) else list(estimate)
    names = list(labels) if labels is not None else [_source(e) for e in estimates]
    rows = [{"label": name, **row} for name, e in zip(names, estimates, strict=True) for row in to_records(e)]
    return pd.DataFrame(rows)


def _source(estimate: Estimate) -> str:
    session: Mapping[str, Any] = estimate.session or {}
    return str(session.get("source", ""))
