"""Read and check a `bsp_ros/core/estimate/1` result before it is stored."""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import math
import re
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from bsp_ros.clinic.store.curves import CURVE_KEY, check_curve, passive_curves
from bsp_ros.clinic.store.records import ARMS, GROUPS, SOURCES, ParamKey, Quality, Quantity, SessionRecord
from bsp_ros.clinic.store.subject import check_subject_id
from bsp_ros.core.estimate_schema import Estimate, Level
from bsp_ros.core.estimate_schema import Quality as EstimateQuality
from bsp_ros.errors import InputError, StoreError

ESTIMATE_SCHEMA = "bsp_ros/core/estimate/1"
_NAME = re.compile(r"[A-Za-z0-9_+.-]{1,64}")
# Only these subject facts are kept (for anthropometric priors); anything else in a "subject" block is dropped.
SUBJECT_KEYS = ("body_mass_kg", "height_m", "sex")


def load_estimate_file(path: str | Path) -> dict[str, Any]:
    """Read an estimate JSON file.

    Parameters
    ----------
    path : str or Path
        The file `bsp identify --json` wrote.

    Returns
    -------
    dict
        The parsed top-level object (not yet checked against the schema).

    Raises
    ------
    StoreError
        If the file cannot be read, is not JSON, or its top level is not an object.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise StoreError(f"cannot read estimate {path}: {error}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise StoreError(f"{path} is not valid JSON ({error}); expected a {ESTIMATE_SCHEMA} result") from None
    except RecursionError:  # json's decoder gives up on nesting deeper than the interpreter's recursion limit
        raise StoreError(
            f"cannot read estimate {path}: its JSON is nested deeper than {sys.getrecursionlimit()} levels; "
            f"not a {ESTIMATE_SCHEMA} result"
        ) from None
    if not isinstance(data, dict):
        raise StoreError(f"{path} holds a JSON {type(data).__name__}, expected a {ESTIMATE_SCHEMA} object")
    return data


WALL_CLOCK_START_NS = 946_684_800 * 10**9
"""2000-01-01T00:00:00Z: a session stamped earlier was stamped from boot or from 0, not by a wall clock."""
_TIME_HELP = "give the session start with --time (a date 2024-03-01, ISO 8601 2024-03-01T09:30 or epoch seconds)"


def parse_time_ns(text: str) -> int:
    """Parse a session time as users type it: a date, ISO 8601 (naive means UTC), epoch seconds or ns.

    ``2024-03-01``, ``2024-03-01T09:30:00Z``, ``2024-03-01 09:30+01:00``, ``1709285400`` (seconds, may carry a
    fraction) and ``1709285400000000000`` (ns, 17 or more digits) are accepted.

    Raises
    ------
    InputError
        If the text is none of these, or the time is not after 2000-01-01 and before 2200.
    """
    text = text.strip()
    if re.fullmatch(r"\d{17,}", text):
        return _check_time_ns(int(text), "session time")
    if re.fullmatch(r"\d{1,11}(\.\d{1,9})?", text):
        whole, _, fraction = text.partition(".")
        return _check_time_ns(int(whole) * 10**9 + int((fraction or "0").ljust(9, "0")), "session time")
    if re.fullmatch(r"\d+(\.\d+)?", text):
        raise InputError(
            f"session time {text!r} has {len(text.partition('.')[0])} digits: give epoch seconds (10 digits), "
            "ns (19 digits), a date or ISO 8601"
        )
    try:
        moment = dt.datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise InputError(
            f"session time {text!r} is not a date (2024-03-01), ISO 8601 (2024-03-01T09:30:00Z) or epoch seconds"
        ) from None
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=dt.timezone.utc)
    delta = moment - dt.datetime(1970, 1, 1, tzinfo=dt.timezone.utc)
    micros = (delta.days * 86_400 + delta.seconds) * 1_000_000 + delta.microseconds
    return _check_time_ns(micros * 1000, "session time")


def parse_estimate(
    data: Mapping[str, Any],
    subject: str,
    *,
    session_time_ns: int | None = None,
    source: str | None = None,
    arm: str | None = None,
    retest: bool | None = None,
    cell: str | None = None,
) -> SessionRecord:
    """Check an estimate's JSON against `bsp_ros/core/estimate/1` and turn it into a session record.

    The JSON is checked where the typed form would lose what is wrong (a string for a number, an unknown source,
    a block of the wrong type), then read as an :class:`Estimate` (:func:`check_estimate_json`) and recorded
    (:func:`record_from_estimate`, whose parameters this function takes).

    Raises
    ------
    StoreError
        If ``data`` is not an estimate of this schema or a field has the wrong type.
    InputError
        If the subject id or a subject fact is invalid.
    """
    subject = check_subject_id(subject)
    return _record_of(
        check_estimate_json(data),
        data,
        subject,
        session_time_ns=session_time_ns,
        source=source,
        arm=arm,
        retest=retest,
        cell=cell,
    )


def check_estimate_json(data: Any) -> Estimate:
    """The typed estimate of a `bsp_ros/core/estimate/1` JSON object, once its blocks are of the right types.

    Raises
    ------
    StoreError
        If ``data`` is not an object of this schema, or a block, quantity or quality field has the wrong type.
    """
    if not isinstance(data, Mapping):
        raise StoreError(f"an estimate must be a JSON object, got {type(data).__name__}")
    schema = data.get("schema")
    if schema is None:
        raise StoreError(f"foreign JSON: it has no 'schema' key; expected a {ESTIMATE_SCHEMA} result")
    if schema != ESTIMATE_SCHEMA:
        raise StoreError(f"unsupported estimate schema {schema!r}; this store reads {ESTIMATE_SCHEMA}")
    for key in ("session", "subject"):
        _optional_object(data, key)
    _check_quality(data.get("quality"))
    _check_quantities(data)
    try:
        return Estimate.from_json(data)
    except (KeyError, TypeError, ValueError) as error:
        raise StoreError(f"not a {ESTIMATE_SCHEMA} result: {error}") from None


def record_from_estimate(
    estimate: Estimate,
    subject: str,
    *,
    session_time_ns: int | None = None,
    source: str | None = None,
    arm: str | None = None,
    retest: bool | None = None,
    cell: str | None = None,
) -> SessionRecord:
    """The session record of a typed estimate.

    Parameters
    ----------
    estimate : Estimate
        Its ``subject`` (``body_mass_kg``, ``height_m``, ``sex``) and ``session`` (``start_time_ns``, ``source``,
        ``method``, ``config``) blocks are used where given.
    subject : str
        Pseudonymous subject id (checked).
    session_time_ns : int, optional
        Session start (ns since the epoch); overrides ``session.start_time_ns``.
    source : str, optional
        Recording name; overrides ``session.source``. Only its last path component is kept.
    arm, retest, cell : optional
        The measured arm (``left``/``right``), whether the session is a same-day retest, the robot cell;
        override ``session.arm``, ``session.retest``, ``session.cell``.

    The recording's content hash is ``session.content_sha256`` when given (a bag's bytes), else the hash of
    the estimate's own numbers, so the same result file is not stored twice. ``joints.<joint>.passive_curve``
    is kept as a curve and compared at fixed angles (:mod:`bsp_ros.clinic.store.curves`).

    Returns
    -------
    SessionRecord
        The record, not yet stored (``id`` is None).

    Raises
    ------
    StoreError
        If a session field has the wrong type, or a valid estimate holds a non-finite number.
    InputError
        If the subject id or a subject fact is invalid.
    """
    return _record_of(
        estimate,
        estimate.to_json(),
        subject,
        session_time_ns=session_time_ns,
        source=source,
        arm=arm,
        retest=retest,
        cell=cell,
    )


def _record_of(
    estimate: Estimate,
    document: Mapping[str, Any],
    subject: str,
    *,
    session_time_ns: int | None,
    source: str | None,
    arm: str | None,
    retest: bool | None,
    cell: str | None,
) -> SessionRecord:
    """:func:`record_from_estimate`, ``document`` the JSON the estimate was read from (or its own): where no
    recording hash is given its numbers stand for the recording, as written, and it says whether the estimate
    reported its sample count."""
    subject = check_subject_id(subject)
    session = dict(estimate.session or {})
    time_ns = session_time_ns if session_time_ns is not None else session.get("start_time_ns")
    if time_ns is None:
        raise StoreError(f"the estimate has no session.start_time_ns: {_TIME_HELP}")
    if not isinstance(time_ns, int) or isinstance(time_ns, bool):
        raise StoreError(f"session.start_time_ns must be an integer, got {time_ns!r}")
    name = source if source is not None else session.get("source")
    if not isinstance(name, str) or not name.strip():
        raise StoreError("the estimate has no session.source: give the recording name (--source)")
    method = session.get("method", estimate.method if estimate.method else None)
    if method is not None and not isinstance(method, str):
        raise StoreError(f"session.method must be a string, got {method!r}")
    config = session.get("config", estimate.extra.get("config", {}))
    if not isinstance(config, dict):
        raise StoreError(f"session.config must be an object, got {type(config).__name__}")
    version = (estimate.software or {}).get("version")
    if isinstance(version, str) and "bsp_ros_version" not in config:
        # What made the estimate, kept with its configuration: rows of an export join back to the run.
        config = {**config, "bsp_ros_version": version[:40]}
    quality = _quality(estimate.quality, reported_samples=document["quality"].get("n_samples") is not None)
    curves, curve_parameters = passive_curves({j: {CURVE_KEY: c} for j, c in estimate.passive_curves.items()})
    parameters = _parameters(estimate, refuse_non_finite=quality.valid)
    parameters.update(curve_parameters)
    arm = arm if arm is not None else session.get("arm")
    if arm is not None and arm not in ARMS:
        raise InputError(f"arm must be one of {ARMS}, got {arm!r}")
    retest = retest if retest is not None else session.get("retest", False)
    if not isinstance(retest, bool):
        raise StoreError(f"session.retest must be true or false, got {retest!r}")
    cell = cell if cell is not None else session.get("cell", "")
    if not isinstance(cell, str) or (cell and _NAME.fullmatch(cell) is None):
        raise InputError(f"cell must be a short name from A-Z a-z 0-9 _ + . -, got {cell!r:.70}")
    return SessionRecord(
        subject=subject,
        session_time_ns=_check_time_ns(time_ns, "session.start_time_ns"),
        source=_basename(name),
        method=method,
        config=_json_safe(config, "session.config"),
        subject_info=_subject_info(dict(estimate.subject or {}), config),
        estimate_schema=estimate.schema,
        quality=quality,
        parameters=parameters,
        repeatability=_repeatability(estimate.extra.get("repeatability")),
        arm=arm,
        retest=retest,
        cell=cell,
        content_sha256=_content_sha256(document, session),
        passive_curves=curves,
        passive_model=_passive_model_used(estimate),
    )


def _passive_model_used(estimate: Estimate) -> str | None:
    # The model used, beside the configured one: with auto or the elastic fallback the data chose it.
    used = (estimate.diagnostics or {}).get("passive_model")
    return used if isinstance(used, str) and used else None


def _content_sha256(document: Mapping[str, Any], session: Mapping[str, Any]) -> str:
    given = session.get("content_sha256")
    if isinstance(given, str) and re.fullmatch(r"[0-9a-f]{64}", given):
        return given
    # No recording hash: the estimate's numbers stand for the recording (the same file added twice).
    body = {k: document.get(k) for k in ("segments", "joints", "quality")}
    text = json.dumps(body, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def check_future(time_ns: int, now_ns: int, name: str = "session time") -> int:
    """Return ``time_ns`` unless it lies after ``now_ns`` (plus 15 min of clock difference)."""
    if time_ns > now_ns + FUTURE_TOLERANCE_NS:
        raise InputError(
            f"{name} {format_time_short(time_ns)} is in the future (now {format_time_short(now_ns)}); "
            "a session cannot be stored before it happened: check the date (naive times are UTC; add the offset, "
            "e.g. 2024-03-01T09:30+01:00)"
        )
    return time_ns


FUTURE_TOLERANCE_NS = 15 * 60 * 10**9
"""Clocks of recording PCs differ: a session time up to 15 min ahead of this machine's clock is accepted."""


def format_time_short(time_ns: int) -> str:
    """``2024-03-01 09:30 UTC``."""
    moment = dt.datetime(1970, 1, 1, tzinfo=dt.timezone.utc) + dt.timedelta(microseconds=time_ns // 1000)
    return moment.strftime("%Y-%m-%d %H:%M UTC")


def _check_time_ns(time_ns: int, name: str) -> int:
    # 2000 < t < 2200: robot controllers and simulated time stamp from boot or from 0; that is no session date.
    if not 0 <= time_ns < 7_258_118_400 * 10**9:
        raise InputError(f"{name} {time_ns} ns is not a plausible time since the epoch")
    if time_ns < WALL_CLOCK_START_NS:
        raise InputError(
            f"{name} {time_ns} ns is {time_ns / 1e9:.6g} s after 1970-01-01, before 2000: not a wall-clock time "
            f"(stamped from boot or from 0?); {_TIME_HELP}"
        )
    return time_ns


def _basename(name: str) -> str:
    base = re.split(r"[\\/]", name.strip().rstrip("/\\"))[-1]
    if not base:
        raise StoreError(f"session source {name!r} has no file name")
    return base[:255]


def _optional_object(data: Mapping[str, Any], key: str) -> dict[str, Any]:
    value = data.get(key, {})
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise StoreError(f"'{key}' must be an object, got {type(value).__name__}")
    return value


def _subject_info(block: Mapping[str, Any], config: Mapping[str, Any]) -> dict[str, Any]:
    given = {key: block.get(key, config.get(key)) for key in SUBJECT_KEYS}
    given = {key: value for key, value in given.items() if value is not None}
    if not given:
        return {}
    # Imported here: the anthropometric tables pull in numpy, which the store itself does not need.
    from bsp_ros.core.anthropometry import check_body_mass_kg, check_height_m, check_sex

    checks: dict[str, Callable[[Any], Any]] = {
        "body_mass_kg": check_body_mass_kg,
        "height_m": check_height_m,
        "sex": check_sex,
    }
    return {key: checks[key](value) for key, value in given.items()}


def _finite_or_none(value: Any, name: str, *, refuse_non_finite: bool = False) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise StoreError(f"{name} must be a number or null, got {value!r}")
    number = float(value)
    if not math.isfinite(number) and refuse_non_finite:
        raise StoreError(
            f"{name} is {number} in an estimate marked valid: a valid estimate holds finite numbers "
            "(or null where it has none); not stored"
        )
    return number if math.isfinite(number) else None


def _check_quantities(data: Mapping[str, Any]) -> None:
    """Each ``segments``/``joints`` entry of an estimate's JSON an object of well-named quantities (``value`` and
    ``std`` numbers or null, a known ``source``), and its curves well-formed."""
    for group in GROUPS:
        parts = data.get(group)
        if not isinstance(parts, dict):
            raise StoreError(f"not a {ESTIMATE_SCHEMA} result: '{group}' must be an object")
        for part, quantities in parts.items():
            if _NAME.fullmatch(part) is None or not isinstance(quantities, dict):
                raise StoreError(f"{group}.{part!s:.64} must be an object named by a short key")
            for quantity, q in quantities.items():
                if group == "joints" and quantity == CURVE_KEY:
                    check_curve(str(part), q)  # a curve, not a quantity: see passive_curves
                    continue
                where = f"{group}.{part}.{quantity}"
                if _NAME.fullmatch(quantity) is None:
                    raise StoreError(f"{group}.{part} has a malformed quantity key {quantity!r:.70}")
                if not isinstance(q, dict) or "value" not in q or "std" not in q:
                    raise StoreError(f"{where} must be an object with 'value', 'std' and 'source'")
                if q.get("source") not in SOURCES:
                    raise StoreError(f"{where}.source must be one of {SOURCES}, got {q.get('source')!r}")
                _finite_or_none(q["std"], f"{where}.std")
                _finite_or_none(q["value"], f"{where}.value")
                if q.get("budget") is not None and not isinstance(q["budget"], dict):
                    raise StoreError(f"{where}.budget must be an object of term: number, got {q['budget']!r:.70}")


def _parameters(estimate: Estimate, *, refuse_non_finite: bool) -> dict[ParamKey, Quantity]:
    """Every quantity of ``estimate`` as stored: non-finite numbers as None (refused in a valid estimate)."""
    parameters: dict[ParamKey, Quantity] = {}
    for group, part, key, q in estimate.quantities():
        where = f"{group}.{part}.{key}"
        std = _finite_or_none(q.std, f"{where}.std", refuse_non_finite=refuse_non_finite)
        if std is not None and std < 0.0:
            raise StoreError(f"{where}.std must not be negative, got {std}")
        value = _finite_or_none(q.value, f"{where}.value", refuse_non_finite=refuse_non_finite)
        budget = None if q.budget is None else _budget(q.budget, f"{where}.budget")
        parameters[(group, part, key)] = Quantity(value=value, std=std, source=q.source, budget=budget)
    if not parameters:
        raise StoreError("the estimate holds no parameters")
    return parameters


def _budget(budget: Mapping[str, Any], where: str) -> dict[str, float | None]:
    """A quantity's uncertainty budget as stored: each term a short key, its standard uncertainty a non-negative
    number (a non-finite one as None, as a std is)."""
    kept: dict[str, float | None] = {}
    for term, u in budget.items():
        if not isinstance(term, str) or _NAME.fullmatch(term) is None:
            raise StoreError(f"{where} has a malformed term {term!r:.70}")
        number = _finite_or_none(u, f"{where}.{term}")
        if number is not None and number < 0.0:
            raise StoreError(f"{where}.{term} must not be negative, got {number}")
        kept[term] = number
    return kept


def _check_quality(block: Any) -> None:
    """The ``quality`` block of an estimate's JSON of the right types."""
    if not isinstance(block, dict):
        raise StoreError(f"not a {ESTIMATE_SCHEMA} result: 'quality' must be an object")
    valid = block.get("valid")
    if not isinstance(valid, bool):
        raise StoreError(f"quality.valid must be true or false, got {valid!r}")
    n_samples = block.get("n_samples")
    if n_samples is not None and (not isinstance(n_samples, int) or isinstance(n_samples, bool)):
        raise StoreError(f"quality.n_samples must be an integer, got {n_samples!r}")
    residuals = block.get("residual_rms_nm", {}) or {}
    if not isinstance(residuals, dict):
        raise StoreError("quality.residual_rms_nm must be an object of joint: number")
    for k, v in residuals.items():
        _finite_or_none(v, f"residual_rms_nm.{k}")
    warnings = block.get("warnings", []) or []
    if not isinstance(warnings, list) or not all(isinstance(w, str) for w in warnings):
        raise StoreError("quality.warnings must be a list of strings")
    tare = block.get("tare") or {}
    if not isinstance(tare, dict) or not isinstance(tare.get("applied", False), bool):
        raise StoreError(f"quality.tare must be an object with 'applied': true or false, got {tare!r:.80}")
    findings = block.get("findings", []) or []
    if not isinstance(findings, list) or not all(isinstance(f, dict) for f in findings):
        raise StoreError("quality.findings must be a list of objects")
    level = block.get("level")
    if level is not None and level not in {str(v) for v in Level}:
        raise StoreError(f"quality.level must be one of {[str(v) for v in Level]}, got {level!r:.40}")


def _quality(quality: EstimateQuality, *, reported_samples: bool) -> Quality:
    """The stored form of an estimate's quality (``reported_samples``: its sample count was given)."""
    tare_file = quality.tare_file
    return Quality(
        message=quality.message[:2000],
        valid=quality.valid,
        tare_applied=quality.tare_applied,
        tare_file=_basename(tare_file) if tare_file is not None and tare_file.strip() else None,
        n_samples=quality.n_samples if reported_samples else None,
        condition_number=_finite_or_none(quality.condition_number, "quality.condition_number"),
        residual_rms_nm={k: v for k, v in quality.residual_rms_nm.items() if math.isfinite(v)},
        warnings=quality.warnings,
        findings=quality.findings,
    )


def _repeatability(block: Any) -> dict[str, Any]:
    """The estimate's ``repeatability`` block (see bsp_ros.clinic.mdc), checked; entries without a finite SEM
    dropped."""
    if block is None:
        return {}
    if not isinstance(block, dict):
        raise StoreError(f"'repeatability' must be an object, got {type(block).__name__}")
    method = block.get("method")
    if not isinstance(method, str) or not method.strip():
        raise StoreError("repeatability.method must name how the SEM was obtained")
    entries = block.get("parameters", {}) or {}
    if not isinstance(entries, dict):
        raise StoreError("repeatability.parameters must be an object of parameter: {sem, mdc95, n}")
    parameters: dict[str, Any] = {}
    for key, entry in entries.items():
        parts = str(key).split(".")
        if len(parts) != 3 or parts[0] not in GROUPS or not all(_NAME.fullmatch(p) for p in parts[1:]):
            raise StoreError(f"repeatability.parameters has a malformed key {key!r:.70} (want group.part.quantity)")
        if not isinstance(entry, dict):
            raise StoreError(f"repeatability.parameters.{key} must be an object")
        sem = _finite_or_none(entry.get("sem"), f"repeatability.parameters.{key}.sem")
        if sem is None:
            continue
        if sem < 0:
            raise StoreError(f"repeatability.parameters.{key}.sem must not be negative, got {sem}")
        n = entry.get("n")
        parameters[key] = {
            "sem": sem,
            "mdc95": 1.96 * math.sqrt(2.0) * sem,
            "n": n if isinstance(n, int) and not isinstance(n, bool) else None,
        }
    counts = {k: block.get(k) for k in ("n_cycles", "n_valid_cycles")}
    message = block.get("message", "")
    return {
        "method": method[:2000],
        "parameters": parameters,
        **{k: v for k, v in counts.items() if isinstance(v, int) and not isinstance(v, bool)},
        "message": message[:2000] if isinstance(message, str) else "",
    }


def _json_safe(value: Any, name: str) -> Any:
    """``value`` with non-finite floats replaced by None, so it round-trips through strict JSON."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): _json_safe(v, name) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_safe(v, name) for v in value]
    if value is None or isinstance(value, str | int | bool):
        return value
    raise StoreError(f"{name} holds a {type(value).__name__}, which is not JSON")
