"""Effects the model lacks: Stribeck-like friction makes the estimate invalid, named; a drifting sensor is named and
modelled."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.joint.outliers import near_gaps
from bsp_ros.core.identification.result import IdentificationResult


def identified(seed: int, **changes: object) -> IdentificationResult:
    """60 s of the human arm with sensor or passive changes (``sensor__name`` / ``passive__name``)."""
    spec = sim.human_arm_cell(seed=seed, duration_s=60.0)
    sensor = {k.removeprefix("sensor__"): v for k, v in changes.items() if k.startswith("sensor__")}
    passive = {k.removeprefix("passive__"): v for k, v in changes.items() if k.startswith("passive__")}
    spec = dataclasses.replace(
        spec,
        sensor=dataclasses.replace(spec.sensor, **sensor),  # type: ignore[arg-type]
        passive=dataclasses.replace(spec.passive, **passive),  # type: ignore[arg-type]
    )
    # The simulated markers sit on the joint centres: no placement uncertainty for the effects to hide in.
    data = identification_data_from_session(sim.simulate_cell(spec).session)
    return identify_joint(data, JointConfig(marker_placement_sd_m=0.0))


@pytest.mark.parametrize("seed", [0, 1])
def test_a_clean_session_shows_neither_drift_nor_speed_dependent_friction(seed: int) -> None:
    result = identified(seed)
    assert result.valid, result.message
    codes = [f.code for f in result.findings]
    assert FindingCode.DRIFT_MODELLED not in codes and FindingCode.FRICTION_SPEED_DEPENDENT not in codes, codes


def test_a_drifting_force_sensor_is_named_and_modelled_within_its_std() -> None:
    """10 mN/s along world y and z: 0.6 N over the minute. It was made invalid (a right result thrown away where
    the std could hold it); now the drift's rate is fitted and what its unknown level leaves open joins the std:
    valid, named, the truth within 3 std."""
    spec = sim.human_arm_cell(seed=2, duration_s=60.0)
    spec = dataclasses.replace(spec, sensor=dataclasses.replace(spec.sensor, force_drift_n_per_s=(0.0, 0.007, 0.007)))
    simulated = sim.simulate_cell(spec)
    data = identification_data_from_session(simulated.session)
    result = identify_joint(data, JointConfig(marker_placement_sd_m=0.0))
    assert result.valid, result.message
    drifts = [f for f in result.findings if f.code is FindingCode.DRIFT_MODELLED]
    assert drifts and not drifts[0].values["drift_recording"], result.warnings
    _, beta, cov = result.block("static_moment_kgm")
    truth = np.asarray(simulated.truth.static_moments_kgm)
    z = np.abs(beta - truth) / np.sqrt(np.diag(cov))
    assert (z < 3.0).all(), z


def test_stribeck_like_friction_makes_the_estimate_invalid_and_names_the_joint() -> None:
    """Friction 1.5 times larger below 10 mrad/s: a sign step's amplitude is then a speed-dependent average."""
    result = identified(3, passive__stribeck_ratio=1.5, passive__stribeck_speed_rad_s=0.01)
    assert not result.valid
    assert any(f.code is FindingCode.FRICTION_SPEED_DEPENDENT and f.where == "elbow" for f in result.findings)
    assert FindingCode.UNMODELLED_EFFECT in [f.code for f in result.findings] or result.valid


def test_samples_far_off_the_fit_next_to_marker_gaps_are_named_as_such() -> None:
    # Marker dropouts (5 %, 20 frames on average) leave gaps in the angles; at their edges the direction
    # of motion is least certain and a few samples get friction's sign wrong (seed 0: 9 such samples).
    spec = sim.human_arm_cell(seed=0, duration_s=120.0)
    spec = dataclasses.replace(
        spec, markers=dataclasses.replace(spec.markers, dropout_fraction=0.05, dropout_mean_frames=20.0)
    )
    result = identify_joint(identification_data_from_session(sim.simulate_cell(spec).session))
    assert result.valid, result.message
    far = [f.text for f in result.findings if f.code is FindingCode.FIT_OUTLIERS_REMOVED]
    assert len(far) == 1 and "of a gap in the joint angles (marker dropouts" in far[0], result.warnings
    # A note on these samples, not on the model: a live refit of newer samples does not inherit it.
    assert result.held is not None and far[0] not in result.held.warnings


def test_near_gaps_marks_the_samples_beside_a_gap_only() -> None:
    t_ns = np.concatenate(
        [np.arange(0, 1_000_000_000, 10_000_000), np.arange(2_000_000_000, 3_000_000_000, 10_000_000)]
    )
    near = near_gaps(t_ns, 0.05)
    # The last 6 samples before the gap (0.94-0.99 s) and the first 6 after it (2.00-2.05 s).
    assert np.flatnonzero(near).tolist() == [*range(94, 100), *range(100, 106)]


@pytest.mark.parametrize("stribeck_ratio", [1.0, 1.5])
def test_a_term_test_skips_the_covariance_only_of_a_term_that_cannot_count(stribeck_ratio: float) -> None:
    """term_test looks at the wider fit's values first and computes its HAC covariance only when a watched
    parameter moves by more than the base std: a skipped term must be one the full test does not count either,
    and a term it tests must get the full test's numbers. The terms: a low-speed friction excess at each joint
    (the simulated arm has it at every joint with ``stribeck_ratio`` 1.5, at none with 1)."""
    from bsp_ros.core.identification.joint.samples import usable_samples
    from bsp_ros.core.identification.joint.unmodelled import MODEL_CHECK_P, MODEL_CHECK_SHIFT_SD, term_test
    from bsp_ros.core.identification.stacked import fit_problem

    spec = sim.human_arm_cell(seed=3, duration_s=60.0)
    passive = dataclasses.replace(spec.passive, stribeck_ratio=stribeck_ratio, stribeck_speed_rad_s=0.01)
    data = identification_data_from_session(sim.simulate_cell(dataclasses.replace(spec, passive=passive)).session)
    config = JointConfig(marker_placement_sd_m=0.0)
    problem = usable_samples(data, config).problem
    fit = fit_problem(problem)
    n, k = data.n_joints, len(config.passive.local)
    outcomes = []
    for j in range(n):
        extra = np.zeros((data.t_ns.size, n, 1))
        for speed_rad_s in (0.004, 0.016):
            velocity = data.velocity_rad_s[:, j]
            extra[:, j, 0] = np.sign(velocity) * np.exp(-((velocity / speed_rad_s) ** 2))
            watched = [n + j * k + config.passive.local.index("coulomb"), *range(n)]
            gated = term_test(problem, fit, extra, [("stribeck_nm", "joint")], watched)
            full = term_test(problem, fit, extra, [("stribeck_nm", "joint")], watched, can_count=lambda values: True)
            assert full is not None
            counts = full.p_value < MODEL_CHECK_P and full.shift_sd > MODEL_CHECK_SHIFT_SD
            outcomes.append("skipped" if gated is None else "counts" if counts else "tested")
            if gated is None:
                assert not counts
            else:
                assert (gated.p_value, gated.shift_sd, gated.worst) == (full.p_value, full.shift_sd, full.worst)
                np.testing.assert_array_equal(gated.wide.covariance, full.wide.covariance)
    if stribeck_ratio == 1.0:
        assert "skipped" in outcomes and "counts" not in outcomes, outcomes  # the gate saves work on a clean arm
    else:
        assert "counts" in outcomes, outcomes


@pytest.mark.parametrize("elbow_stiffness_nm_per_rad", [0.0, 1.0])
def test_the_elastic_check_skips_the_placement_share_only_where_it_cannot_change_the_verdict(
    elbow_stiffness_nm_per_rad: float, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The marker placement's share only adds variance to the elastic terms': terms insignificant without it stay
    so with it, and the check skips computing it there. Its notes must be those of always computing it."""
    import bsp_ros.core.identification.joint.elastic_check as check_module
    from bsp_ros.core.identification.joint.placement_covariance import placement_covariance
    from bsp_ros.core.identification.joint.samples import usable_samples
    from bsp_ros.core.identification.stacked import fit_problem

    passive = sim.PassiveTruth(
        coulomb_nm=(0.5, 0.28, 0.06),
        stiffness_nm_per_rad=(0.0, elbow_stiffness_nm_per_rad, 0.0),
        neutral_rad=(0.0, np.radians(107.0), 0.0),
    )
    data = identification_data_from_session(sim.simulate_cell(sim.human_arm_cell(seed=5, passive=passive)).session)
    config = JointConfig()
    samples = usable_samples(data, config)
    base = fit_problem(samples.problem)
    sd_m = config.placement_sd_m(data.n_joints, data.contact_from_robot)
    calls = []

    def with_placement(problem, fit):  # type: ignore[no-untyped-def]
        calls.append(1)
        return fit.covariance + placement_covariance(data, problem, fit, sd_m)

    def notes() -> list[str]:
        widths = np.zeros(data.n_joints)
        return check_module.elastic_check(data, config, samples.rows, base, widths, samples.extras, with_placement)

    gated = notes()
    gated_calls = len(calls)
    monkeypatch.setattr(check_module, "_surely_insignificant", lambda *args: None)
    assert gated == notes()
    if elbow_stiffness_nm_per_rad == 0.0:
        assert gated == [] and gated_calls == 0
    else:
        assert any(note.code is FindingCode.ELASTIC_TERM and note.where == "elbow" for note in gated), gated
