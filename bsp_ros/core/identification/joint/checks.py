"""The model checks of the stacked identification, in order: friction at low speed, an elastic moment the model
lacks, the markers' placement, resistance growing with speed in one direction (spasticity), an implausible off-axis
moment. Each finds what the model lacks on a fit that the
data support; what it finds makes the estimate invalid or widens its std (a named term of the ledger)."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.joint.elastic_check import elastic_check
from bsp_ros.core.identification.joint.fallback import family_result
from bsp_ros.core.identification.joint.judgement import static_moments_at_bound, unbounded_static_moments
from bsp_ros.core.identification.joint.placement_scale import placement_scale
from bsp_ros.core.identification.joint.spasticity import speed_dependence
from bsp_ros.core.identification.joint.stage import Outcome, Stage
from bsp_ros.core.identification.joint.steps import with_drift_terms, with_placement
from bsp_ros.core.identification.joint.stribeck import stribeck_check
from bsp_ros.core.identification.ledger import Term
from bsp_ros.core.identification.priors import implausible_perpendicular_moments
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.identification.stacked import build_problem
from bsp_ros.core.streams import joints_for

__all__ = ["check_elastic", "check_perpendicular", "check_placement", "check_spasticity", "check_stribeck"]

# Speed-dependent resistance below this is not named (it moves no estimate a clinic reads), Nm.
MIN_SPASTIC_NM = 0.02


def check_stribeck(stage: Stage) -> Stage:
    """Friction larger at low speed: named; where modelling it moves the estimate beyond its std the estimate is
    invalid, else which friction law holds is open and both amplitudes join the Coulomb variance."""
    if not stage.config.check_elastic or stage.problems:
        return stage
    found = stribeck_check(stage.data, stage.problem, stage.fit, stage.config, stage.widths_rad_s)
    biasing = tuple(f.note for f in found if f.biases_estimate)
    term = np.zeros_like(stage.fit.covariance)
    for finding in (f for f in found if not f.biases_estimate):
        term[finding.coulomb_column, finding.coulomb_column] += finding.coulomb_shift_nm**2
    outcome = Outcome(
        added=((Term.FRICTION_SHAPE, term),) if term.any() else (),
        notes=(*biasing, *(f.note for f in found if not f.biases_estimate)),
        problems=(Finding(code=FindingCode.UNMODELLED_EFFECT),) if biasing else (),
    )
    return stage.apply(outcome, from_checks=True)


def _with_springs(stage: Stage) -> Stage:
    """``stage`` with the model that has a linear spring's terms beside this one's: the elastic check's wider
    model, and what the placement check fits beside the offsets (built once, where either needs it)."""
    springs = "offset" in stage.config.passive.terms  # an elastic model: every elastic term needs the offset
    if springs or stage.problems or stage.with_springs is not None:
        return stage
    if not (stage.config.check_elastic or stage.placement is not None):
        return stage
    wider = stage.config.passive.with_terms(("offset", "stiffness"))
    problem = build_problem(stage.data, wider, stage.problem.rows, stage.widths_rad_s, stage.samples.extras)
    return dataclasses.replace(stage, with_springs=problem)


def check_elastic(stage: Stage) -> Stage | IdentificationResult:
    """A linear spring the fixed model lacks that the data support and that moves the static moments: the family
    the data choose from replaces the model (``elastic_fallback``), or the estimate is invalid."""
    stage = _with_springs(stage)
    config = stage.config
    if not config.check_elastic or stage.selection is not None or stage.problems:
        return stage
    elastic = elastic_check(
        stage.data,
        config,
        stage.problem.rows,
        stage.fit,
        stage.widths_rad_s,
        stage.samples.extras,
        functools.partial(with_placement, stage),
        stage.with_springs,
    )
    if elastic and config.elastic_fallback:
        # The data reject the fixed model: the family the data choose from, its spread in the std, replaces it.
        return family_result(stage.given, config).with_findings(*elastic, first=True)
    problems = (Finding(code=FindingCode.ELASTIC_LACKING),) if elastic else ()
    return stage.apply(Outcome(notes=tuple(elastic), problems=problems), from_checks=True)


def check_placement(stage: Stage) -> Stage:
    """Whether the data put the markers further off their joint centres than assumed (placement_scale.py): where
    they do, the wider placement's share replaces the assumed one.

    Last of the checks that change the std, since free offsets take up what else the model lacks (a spring, a drift,
    a low-speed friction), which must change the model or the verdict, not only widen the std. So it is not judged
    where a check found something, nor with an elastic model (on one posture its terms, gravity and the offsets are
    nearly one: MuJoCo arms with springs and their markers on the centres read as 6-10 mm off); and a spring or
    drift too small for its own check is fitted beside the offsets (taken up, it read as 10-20 mm).
    """
    stage = _with_springs(stage)
    placement = stage.placement
    if placement is None or "offset" in stage.config.passive.terms or stage.problems:
        return stage
    assert stage.with_springs is not None  # built for the same conditions
    stage = with_drift_terms(stage)
    assert stage.drift_terms is not None
    skin = np.ones(stage.n + 1, dtype=bool)
    skin[-1] = not stage.data.contact_from_robot
    found = placement_scale(
        stage.problem, placement.columns, stage.placement_sd_m, skin, stage.with_springs, stage.drift_terms[:2]
    )
    stage = dataclasses.replace(stage, placement_check=found)
    if found.scale <= 1.0:
        return stage
    wider = placement.covariance_scaled(found.column_factor)
    notes = (found.note,) if found.note is not None else ()
    return stage.apply(Outcome(replaced=((Term.MARKER_PLACEMENT, wider),), notes=notes), from_checks=True)


def check_spasticity(stage: Stage) -> Stage:
    """Resistance that grows with speed in one direction of motion only (:func:`speed_dependence`): named as
    possible spasticity at that joint, beside the estimate (also where an earlier check found the friction's speed
    dependence invalidating: spasticity may be its cause)."""
    if not stage.config.check_elastic or stage.data_problems:
        return stage
    notes = []
    for j, joint in enumerate(joints_for(stage.n)):
        found = speed_dependence(stage.data.t_ns, stage.data.velocity_rad_s[:, j], stage.fit.residual[:, j])
        if found.direction and found.increase_nm > MIN_SPASTIC_NM:
            values = {"increase_nm": found.increase_nm, "fast_rad_s": found.fast_rad_s, "direction": found.direction}
            notes.append(Finding(code=FindingCode.SPASTICITY, where=joint, values=values))
    return stage.apply(Outcome(notes=tuple(notes)), from_checks=True)


def check_perpendicular(stage: Stage) -> Stage:
    """Last, with the model checks (live, they run beside the updates): an off-axis moment no real centre of mass
    gives; a drift or an elastic term the checks above name is the likelier cause of one."""
    extras = stage.samples.extras
    if not stage.config.check_elastic or extras is None or stage.problems:
        return stage
    names = stage.problem.names
    perpendicular = [i for i, (key, _) in enumerate(names) if key == "perpendicular_moment_kgm"]
    model = stage.ledger.get(Term.MODEL_CHOICE)
    placed = stage.ledger.get(Term.MARKER_PLACEMENT)
    slipped = stage.ledger.get(Term.CONTACT_SLIP)
    if slipped is not None:  # what following a slipping hand leaves open is no evidence of a missing moment either
        model = slipped if model is None else model + slipped
    model_sd = np.zeros(len(names)) if model is None else np.sqrt(np.clip(np.diag(model), 0.0, None))
    placement_sd = np.zeros(len(names)) if placed is None else np.sqrt(np.clip(np.diag(placed), 0.0, None))
    segments = [names[i][1] for i in perpendicular]

    def implausible(values: np.ndarray) -> list[Finding]:
        return implausible_perpendicular_moments(
            segments,
            values[perpendicular],
            extras.prior,
            # A marker off its joint centre, normal to the segment, tilts the segment's angle: an apparent off-axis
            # moment as large as the placement std says, no evidence of a missing moment.
            np.hypot(model_sd[perpendicular], placement_sd[perpendicular]),
            family_chosen=stage.config.passive.select,
        )

    problems = implausible(stage.fit.values)
    bounded = {names[i][1] for i in np.flatnonzero(static_moments_at_bound(stage))}
    if not any(f.where in bounded for f in problems):
        return stage.apply(Outcome(problems=tuple(problems)), from_checks=True)
    # A static moment held at its bound 0 pushes what the data put below it into its segment's off-axis moment (a
    # contact marker 1.5 mm off the hand's axis did, in short sessions of a light hand): judged on the data's own
    # fit, which the static moment's verdict reads too, and the push joins the covariance.
    own = unbounded_static_moments(stage.problem)
    still = {f.where for f in implausible(own)}
    problems = [f for f in problems if f.where not in bounded or f.where in still]
    push = stage.fit.values - own
    added = () if problems else ((Term.STATIC_MOMENT_BOUND, np.outer(push, push)),)
    return stage.apply(Outcome(problems=tuple(problems), added=added), from_checks=True)
