"""The table behind :mod:`bsp_ros.core.findings`: each code's severity, text, and cause and action in plain words."""

from __future__ import annotations

from bsp_ros.core.findings import Finding, FindingCode, FindingSpec, Severity

__all__ = ["SPECS"]

C = FindingCode
INVALID, WEAK, NOTE = Severity.INVALID, Severity.WEAK, Severity.NOTE

_REPEAT = "repeat with the planned movement (bsp plan)"
_SENSOR = "check the force sensor (zero it with a tare) and the markers, then repeat"
_MODEL = "the arm resisted in a way the chosen model does not describe"


def _plural(count: int, word: str) -> str:
    return f"{count} {word}{'s' if count != 1 else ''}"


def _too_few(f: Finding) -> str:
    v = f.values
    if "min_samples" in v:
        return f"too few samples: {v['n']} < {v['min_samples']}"
    if "updates" in v:
        return f"too few samples: {v['updates']} updates"
    return "too few samples"


def _one_direction(f: Finding) -> str:
    if not f.where:
        return "each joint must move both ways"
    return f"the {f.where} moved in one direction only ({f.values['other_percent']:.1f}% of rows the other way)"


def _stale(f: Finding) -> str:
    v = f.values
    if v.get("newest"):
        return f"stale input: newest {v['what']} is {v['silent_s']:.2f} s old"
    return f"stale input: no {v['what']} for {v['silent_s']:.2f} s"


def _misfit_how(rms_nm: float, ratio: float, noise_nm: float) -> str:
    return f"residual RMS {rms_nm:.3g} Nm is {ratio:.1f} times the sensor noise ({noise_nm:.2g} Nm)"


def _misfit(f: Finding) -> str:
    v = f.values
    return (
        f"the model does not fit at the {f.where}: {_misfit_how(v['rms_nm'], v['ratio'], v['noise_nm'])} the data "
        "shows (a missing or wrong sensor transform, an unmodelled load or passive moment?)"
    )


def _grip(f: Finding) -> str:
    v = f.values
    joints = f"; {v['n_joints']} joints stuck" if v["n_joints"] > 1 else ""
    return (
        f"the hand gave in the strap: the {f.where} stood still for {v['stick_s']:.1f} s at a time, "
        f"{v['dwell_ratio']:.1f} times as long as a turn of the movement takes ({v['stuck_percent']:.0f} % of the "
        f"session{joints}), until the strap had loaded it past its friction; those stretches were left out of the "
        "friction fit"
    )


def _family_chosen(f: Finding) -> str:
    v = f.values
    where = "; ".join(
        f"at the {joint}, {_misfit_how(rms, ratio, noise)}"
        for joint, rms, ratio, noise in zip(v["joints"], v["rms_nm"], v["ratio"], v["noise_nm"], strict=True)
    )
    return (
        f"the {v['model']} passive model does not fit ({where}); with the elastic terms the data choose "
        "(--passive auto) the model fits: the estimate uses them, and what that choice leaves open is in its std"
    )


def _fit_outliers(f: Finding) -> str:
    v = f.values
    n, near = int(v["n"]), int(v.get("near_gap", 0))
    where = (
        f"; {near} of them within {v['gap_edge_s']:g} s of a gap in the joint angles (marker dropouts: the "
        "direction of motion, hence the sign of friction, is least certain there)"
        if near
        else ""
    )
    return (
        f"removed {n} sample{'s' if n > 1 else ''} far off the fit (residual over {v['outlier_sd']:g} robust sd){where}"
    )


def _spikes(f: Finding) -> str:
    v = f.values
    n = int(v["n"])
    return (
        f"removed {n} wrench sample{'s' if n > 1 else ''} off the local robust spread (joint torques more "
        f"than {v['outlier_sd']:g} robust sd from the rolling median of {v['window']} samples)"
    )


def _elastic_term(f: Finding) -> str:
    v = f.values
    fallback = bool(v["fallback"])
    return (
        f"elastic passive moment at the {f.where}: {v['kinds']} terms the model lacks are supported by "
        f"the data (chi2 {v['chi2']:.0f}) and confounded with gravity (|corr| {v['corr']:.2f}); modelling them "
        f"moves the {v['segment']} static moment by {v['change_percent']:.1f}% "
        f"({v['shift_sd']:.1f} std): "
        + (
            "the estimate uses the elastic terms the data choose (--passive auto), and what that choice "
            "leaves open is in its std"
            if fallback
            else "the static moments may be biased (try --passive auto, which chooses the elastic terms and "
            "puts what the choice leaves open in the std"
        )
        + "; an F/T sensor offset no tare removed looks like an elastic offset: apply one with --tare"
        + ("" if fallback else ")")
    )


def _speed_dependent(f: Finding) -> str:
    v = f.values
    moving = "the joint angle rising" if v["direction"] > 0 else "the joint angle falling"
    measured = (
        f"the {f.where} moved at two speeds ({v['slow_rad_s']:.3g} and {v['fast_rad_s']:.3g} rad/s): moving with "
        f"{moving}, its resistance was {v['part_nm']:+.3g} +- {v['std_nm']:.2g} Nm higher at the fast speed, "
        "beyond the passive model"
    )
    if not v["exceeds"]:
        return f"{measured}: within 3 std of none, so its static moments are the whole session's"
    if not v["static_from_slow"]:
        return f"{measured}: a speed-dependent part, but too little of the slow part is left to identify it alone"
    return f"{measured}: a speed-dependent part, left out: its static moments come from the slow part"


def _stribeck(f: Finding) -> str:
    v = f.values
    if v["moves"] == "static_moment":
        moved = f"moves the {v['segment']} static moment by {v['shift_sd']:.1f} std"
    elif v["moves"] == "coulomb":
        moved = f"moves its Coulomb amplitude by {v['coulomb_sd']:.1f} std"
    else:
        moved = (
            f"moves its Coulomb amplitude by {abs(v['coulomb_shift_nm']):.2g} Nm ({v['coulomb_sd']:.1f} std), which "
            "its std includes"
        )
    return (
        f"friction at the {f.where} depends on speed (Stribeck-like, larger below about "
        f"{v['speed_mrad_s']:.2g} mrad/s): modelling it {moved}; the amplitude of a sign step is a "
        "speed-dependent average here"
    )


def _drift(f: Finding) -> str:
    v = f.values
    where = f" in recording {v['drift_recording']}" if v.get("drift_recording") else " during the session"
    return (
        f"the wrench drifts{where} (an F/T sensor offset changing by about {v['rate_mn_s']:.2g} mN/s, "
        f"{v['amount_n']:.2g} N over {v['span_s']:.0f} s; it would move the {v['segment']} "
        f"static moment by {v['shift_sd']:.1f} std): modelled as a linear drift, with what its unknown level leaves "
        "open in the std; let the sensor warm up and re-tare for a precise session"
    )


def _placement(f: Finding) -> str:
    v = f.values
    widest = ", the most this check allows" if v["at_limit"] else ""
    return (
        f"the markers sit further off their joint centres than the {v['assumed_mm']:.3g} mm the std assumes: the "
        f"torques bend as markers about {v['apparent_mm']:.2g} mm off would (1 sd per axis{widest}; or a passive "
        "moment the model lacks looks like that), and the std holds it; check that the markers sit firmly on "
        "their landmarks (docs/cell-guide.md)"
    )


def _perpendicular(f: Finding) -> str:
    v = f.values
    return (
        f"the {f.where}'s centre of mass would sit {v['prior_sd_off']:.1f} prior sd off its axis "
        f"(perpendicular moment {v['value_kgm']:.3g} kg m): "
        + (
            "an angle-dependent moment that even the coupled, nonlinear passive terms (up to cubic) do not "
            "follow over these ranges looks like gravity on an off-axis mass: the arm's passive moments are "
            "more nonlinear than the model over this motion; narrower ranges, where the terms follow them, "
            "keep the estimate valid"
            if v["family_chosen"]
            else "an angle-dependent moment the model lacks (a two-joint muscle?) looks like gravity on an "
            "off-axis mass on this trajectory: --passive auto chooses the coupled and nonlinear passive "
            "terms, and a protocol that moves the shoulder and the elbow independently (bsp plan) separates "
            "them"
        )
    )


def _implausible(f: Finding) -> str:
    v = f.values
    typical, factor = v["typical_kgm"], v["factor"]
    return (
        f"implausible {f.where} static moment {v['value_kgm']:.3g} kgm: the anthropometric prior expects about "
        f"{typical:.3g} kgm (plausible {typical / factor:.2g} to {typical * factor:.2g})"
    )


def _bag_damaged(f: Finding) -> str:
    v = f.values
    lost = v["lost_messages"] if v["lost_messages"] is not None else "unknown"
    return (
        f"bag damaged: {v['crc_errors']} chunk CRC errors, truncated={bool(v['truncated'])}, {lost} messages lost; "
        "identified from the intact part"
    )


def _possibly_damaged(f: Finding) -> str:
    counts = f.values["implausible"]
    listed = ", ".join(f"{k} {n}" for k, n in counts)
    return (
        f"possible undetected bag damage: chunks carry no CRC and {sum(n for _, n in counts)} implausible samples "
        f"were removed ({listed})"
    )


def _arm_active(f: Finding) -> str:
    """The stretches left out; where an EMG was read, what it showed beside the torque."""
    v = f.values
    text = (
        f"the arm was not relaxed in {v['n_stretches']} stretch(es), {v['active_s']:.1f} s ({v['active_percent']:.0f} "
        f"% of the session"
    )
    torque = f"up to {v['peak_nm']:.2f} N m at the {f.where}" if f.where else "no torque burst"
    if "emg_share_percent" not in v:
        return f"{text}; {torque}): muscle activity the relaxed-arm model lacks, left out"
    text += (
        f"), left out: EMG above its quiet baseline + {v['k_sd']:g} sd in {v['emg_share_percent']:.1f} % of the "
        f"session ({v.get('channels') or 'no channel'}), torque the relaxed-arm model lacks in "
        f"{v['torque_share_percent']:.1f} % ({torque}"
    )
    if v["torque_share_percent"] > 0:
        text += f", {v['confirmed_percent']:.0f} % of it with EMG"
    text += ")"
    if v.get("emg_only_percent", 0.0) > 0:
        text += (
            f"; {v['emg_only_percent']:.1f} % by EMG alone (muscles active without a net torque: co-contraction, or "
            f"too little torque to show)"
        )
    return text


_EMG_PROBLEMS = {
    "no_channels": "it carries no channel",
    "channels_change": "its channels change during the session ({n_other} messages of other channels)",
    "non_finite": "{bad_percent:.0f} % of its samples are not finite (a lead off?)",
    "negative": "{bad_percent:.0f} % of its samples are negative: no envelope (raw EMG?)",
    "too_slow": "{rate_hz:.1f} Hz is too slow for a 100 ms rule (at least {min_hz:g} Hz)",
    "too_short": "{duration_s:.1f} s are too short for a quiet baseline (at least {min_s:g} s)",
}


def _emg_unusable(f: Finding) -> str:
    why = _EMG_PROBLEMS.get(str(f.values.get("problem", "")), "it cannot be read")
    try:
        why = why.format(**f.values)
    except (KeyError, ValueError):
        why = "it cannot be read"
    return f"the EMG envelopes were not used: {why}; active stretches were found from the torque alone"


_DETAIL = "{detail}"

SPECS: dict[FindingCode, FindingSpec] = {
    C.TOO_FEW_SAMPLES: FindingSpec(
        INVALID, _too_few, "the recording was too short or mostly unusable", "record a full session again"
    ),
    C.TOO_FEW_USABLE_SAMPLES: FindingSpec(
        INVALID,
        "too few usable samples: {fewest}",
        "the recording was too short or mostly unusable",
        "record a full session again",
    ),
    C.NO_MOTION: FindingSpec(
        INVALID,
        "no motion at the {where}: range {range_deg:.3f} deg < {min_range_deg} deg",
        "the {where} did not move",
        "check that the robot runs the planned movement, then repeat",
    ),
    C.ONE_DIRECTION: FindingSpec(
        INVALID, _one_direction, "a joint moved in one direction only", "repeat with the full back-and-forth movement"
    ),
    C.DIRECTION_UNCLEAR: FindingSpec(
        INVALID,
        "most samples of the {where} were dropped: only {share_percent:.0f}% move clearly enough to tell the "
        "direction of motion",
        "the {where} moved too little or too unevenly to tell its direction of motion",
        _REPEAT,
    ),
    C.NOT_YET_DETERMINED: FindingSpec(
        INVALID,
        "poor excitation: static moments not yet determined",
        "the movement has not yet separated the arm's weight from joint resistance",
        "let the session run on",
    ),
    C.NOT_IDENTIFIABLE: FindingSpec(
        INVALID,
        "not identifiable: condition number {condition:.3g} (the motion cannot tell some parameters apart; move "
        "each joint over a wider range: bsp plan)",
        "the movement did not separate the arm's weight from joint resistance",
        _REPEAT,
    ),
    C.FAR_OFF_SAMPLES: FindingSpec(
        INVALID,
        "the model does not fit: {n_far} of {usable} samples lie over {outlier_sd:g} robust sd off it",
        "the measurement does not match the arm model",
        _SENSOR,
    ),
    C.TOO_LITTLE_RELAXED: FindingSpec(
        INVALID,
        "the arm was relaxed for only {relaxed_s:.0f} s ({relaxed_percent:.0f} % of the session): muscle activity "
        "in {n_stretches} stretches leaves too little to identify the relaxed arm",
        "the patient's arm was not relaxed for most of the session",
        "ask the patient to let the robot move the arm without helping or resisting, and record again",
    ),
    C.HANGS_ON_FEW_SAMPLES: FindingSpec(
        INVALID,
        "the fit hangs on a few samples: removing {n_far} far off it moves {key} at the {where} by {shift_sd:.1f} std",
        "a few moments of the session decide the result",
        "repeat the session with the arm relaxed and the markers firm",
    ),
    C.MODEL_MISFIT: FindingSpec(INVALID, _misfit, "the measurement does not match the arm model", _SENSOR),
    C.STATIC_MOMENT_AT_BOUND: FindingSpec(
        INVALID,
        "the {where} static moment sits at its bound 0: the data do not support it",
        "a part of the arm could not be measured",
        _SENSOR,
    ),
    C.UNMODELLED_EFFECT: FindingSpec(
        INVALID,
        "the data show an effect the model lacks that biases the estimate (see warnings)",
        _MODEL,
        "repeat; if it recurs, ask for the stiffness model",
    ),
    C.ELASTIC_LACKING: FindingSpec(
        INVALID,
        "an elastic passive moment the model lacks is supported by the data and biases the static moments "
        "(see warnings)",
        _MODEL,
        "repeat; if it recurs, ask for the stiffness model (--passive auto)",
    ),
    C.PERPENDICULAR_IMPLAUSIBLE: FindingSpec(
        INVALID, _perpendicular, _MODEL, "repeat with the planned movement, which moves each joint on its own"
    ),
    C.STATIC_MOMENT_IMPLAUSIBLE: FindingSpec(
        INVALID, _implausible, "the measured weight of the arm is implausible", _SENSOR
    ),
    C.NOT_SAME_ARM: FindingSpec(
        INVALID,
        "the samples are not of the arm the model was chosen for (its parameters differ)",
        "the arm changed during the session",
        "start a new session",
    ),
    C.NON_FINITE: FindingSpec(
        INVALID, "the fit gave no finite estimate", "the measurement could not be evaluated", "repeat the session"
    ),
    C.ROTATION_ASSUMED: FindingSpec(
        INVALID,
        "missing transform world -> {frame} (no /tf_static, /tf or transform topic recorded, no cell mounting "
        "given): the wrench was taken as given in world",
        "the force sensor's orientation was not recorded",
        "record the sensor's transform with the session, or give its mounting with --cell FILE",
    ),
    C.ROTATION_FROM_MOUNTING: FindingSpec(
        NOTE,
        "no transform {world} -> {frame} from {source} within tf_wait_s ({tf_wait_s:g} s): the stated rotation "
        "{stated} = {rotation_xyzw} is used; publish the sensor's transform or check that rotation",
        "the force sensor's orientation was not received: the cell file's mounting was used",
        "publish the sensor's transform, or check the cell file's ft_sensor.rotation_xyzw",
    ),
    C.ROTATION_DISAGREES: FindingSpec(
        WEAK,
        "the transform {world} -> {frame} from {source} is {received_xyzw}, {angle_deg:.1f} deg off the stated "
        "rotation {stated} = {stated_xyzw} (more than {limit_deg:g} deg): the transform is used; set that rotation "
        "to the transform's if the sensor is mounted so",
        "the force sensor's transform and the cell file's mounting disagree",
        "check how the sensor is mounted and set the cell file's ft_sensor.rotation_xyzw to match",
    ),
    C.INPUT_WAITING: FindingSpec(
        INVALID, "waiting for {what}", "the session has not started", "start the robot and the motion capture"
    ),
    C.INPUT_STALE: FindingSpec(
        INVALID,
        _stale,
        "a sensor stream stopped",
        "check the force sensor and motion-capture streams",
    ),
    C.INTERNAL_ERROR: FindingSpec(
        INVALID, "internal error: {error}", "the estimator failed", "report it with the recording"
    ),
    C.INPUT_UNUSABLE: FindingSpec(
        INVALID, _DETAIL, "the latest data cannot be used", "check the force sensor and motion-capture streams"
    ),
    C.WAITING_FOR_CHECK: FindingSpec(
        INVALID,
        "waiting for the first model check of the window",
        "the session has just started",
        "let the session run on",
    ),
    C.WINDOW_WITHOUT_STD: FindingSpec(
        INVALID,
        "the window's estimate has no std for {key} of the {where}",
        "the session's latest stretch could not be evaluated",
        "let the session run on",
    ),
    C.CONFOUNDED: FindingSpec(
        WEAK,
        "confounded: {key} at the {where} is correlated with gravity (|corr| {corr:.3f}); the {segment} static moment "
        "is uncertain by {rel_std:.1%} (wider ranges separate them, best a second recording with the trunk tilted: "
        "bsp plan --trunk-tilt-deg 0 25, then bsp identify UPRIGHT TILTED --trunk-tilt-deg 0 25)",
        "the movement hardly separated the arm's weight from joint resistance",
        "a second recording with the trunk tilted (bsp plan --trunk-tilt-deg 0 25)",
    ),
    C.UNCERTAIN_STATIC_MOMENT: FindingSpec(
        WEAK,
        "uncertain: {where} static moment {value_kgm:.4g} +- {std_kgm:.2g} kgm",
        "the {where}'s weight is measured only roughly",
        "a longer session or wider movements (bsp plan)",
    ),
    C.ELASTIC_TERM: FindingSpec(
        WEAK,
        _elastic_term,
        "the relaxed joint behaves like a spring",
        "record a tare before each session (a sensor offset looks like a spring) and measure every session with the "
        "stiffness model (--passive auto)",
    ),
    C.HAND_SLIPPED: FindingSpec(
        WEAK,
        "the hand moved in the handle by about {slip_mm:.0f} mm during the session (the contact point drifted along "
        "the hand): the torques were corrected for it, and {left_out_s:.0f} s about its slips left out",
        "the hand moved in the handle during the session",
        "tighten the strap so the hand sits against the handle's stop, and record again if it keeps moving",
    ),
    C.SPASTICITY: FindingSpec(
        WEAK,
        "resistance at the {where} grows with the speed of motion in one direction only ({increase_nm:.2f} N m more "
        "at {fast_rad_s:.2f} rad/s): possible spasticity, which the relaxed-arm model does not hold",
        "the joint resisted faster motion in one direction, as spasticity does",
        "compare with a session at the paper's slow speeds; its static moments are the relaxed arm's",
    ),
    C.TREMOR_FRICTION: FindingSpec(
        WEAK,
        "tremor shook the {where} by {angle_deg:.3f} deg RMS at {frequency_hz:.1f} Hz ({speed_percent:.0f} % of its "
        "typical speed): the friction it shows is this session's, lowered by the shaking, and may be less than the "
        "relaxed arm's (its std says by how much)",
        "a tremor shook the joint, which lowers the friction a session shows",
        "compare its friction only with sessions of a similar tremor",
    ),
    C.DIRECTION_NOISY: FindingSpec(
        WEAK,
        "uncertain direction of motion at the {where}: velocity noise {noise_rad_s:.2g} rad/s against a typical "
        "speed of {typical_rad_s:.2g} rad/s",
        "the {where} moved slowly against the marker noise",
        "check that the markers sit firmly",
    ),
    C.FRICTION_SMOOTH: FindingSpec(
        NOTE,
        "friction at the {where} changes direction smoothly (tanh width about {width_mrad_s:.2g} mrad/s, modelled); "
        "{beyond_percent:.0f}% of samples move faster than 3 widths",
    ),
    C.FRICTION_TRANSITION_WEAK: FindingSpec(
        NOTE,
        "the {where} hardly leaves its friction transition ({beyond_percent:.0f}% of samples beyond 3 widths): its "
        "Coulomb amplitude is weakly identified, and its std says by how much",
    ),
    C.FIT_OUTLIERS_REMOVED: FindingSpec(NOTE, _fit_outliers),
    C.TREMOR: FindingSpec(
        NOTE,
        "tremor at {frequency_hz:.1f} Hz: {torque_nm:.3f} N m RMS at the {where} ({angle_deg:.2f} deg RMS in its "
        "angle), taken out of the fit",
        "the patient's arm shook (tremor) during the session",
        "note it for the therapist; a tremor does not change the arm's weight",
    ),
    C.ARM_ACTIVE: FindingSpec(
        NOTE,
        _arm_active,
        "the patient's arm was active during parts of the session",
        "ask the patient to relax; if it recurs, note it for the therapist",
    ),
    C.EMG_UNUSABLE: FindingSpec(
        NOTE,
        _emg_unusable,
        "the muscle (EMG) recording could not be used",
        "check the EMG electrodes and the amplifier's envelope output before the next session",
    ),
    C.WRENCH_SPIKES_REMOVED: FindingSpec(NOTE, _spikes),
    C.MODEL_CHOICE_SPREAD: FindingSpec(
        NOTE,
        "the {where} static moment depends on the passive model the data cannot choose between or on the passive "
        "curves' assumed shape (they differ by up to {shift_sd:.1f} of its data std): that spread is in its std",
    ),
    C.DRIFT_MODELLED: FindingSpec(
        NOTE, _drift, "the force sensor drifted during the session", "let the sensor warm up, zero it and repeat"
    ),
    C.POORLY_EXCITED: FindingSpec(
        NOTE,
        "poorly excited: condition number {condition:.3g} > {max_condition:g}",
        "the movement did not separate the arm's weight from joint resistance well",
        _REPEAT,
    ),
    C.STATIC_MOMENT_OPEN: FindingSpec(
        NOTE,
        "the {where} static moment sits at its bound 0, within 3 std of the data's own estimate ({own_kgm:.3g} kgm): "
        "the motion does not determine it",
    ),
    C.PARAMETER_AT_BOUND: FindingSpec(NOTE, "{key} at the {where} sits at its bound {lower:g}"),
    C.FRICTION_SPEED_DEPENDENT: FindingSpec(NOTE, _stribeck),
    C.PLACEMENT_WIDER: FindingSpec(
        NOTE, _placement, "the markers sat further off the joints than assumed", "check that the markers sit firmly"
    ),
    C.GRIP_COMPLIANT: FindingSpec(
        NOTE,
        _grip,
        "the hand gave in the strap, so a joint stuck where the movement turned",
        "tighten the strap (a firm pad under the palm) so that the hand follows the handle, and record again if a "
        "joint keeps sticking",
    ),
    # The report renders its own line per joint where the part exceeds (clinic/report/speed_lines.py).
    C.SPEED_DEPENDENT_RESISTANCE: FindingSpec(NOTE, _speed_dependent),
    C.ELASTIC_FAMILY_CHOSEN: FindingSpec(NOTE, _family_chosen),
    C.HELD_FROM_CHECK: FindingSpec(
        NOTE,
        "held from the previous model check, which found it: one check that misses it does not clear it (the windows "
        "the checks judge share most of their samples); the next check decides",
    ),
    C.FUSION_FAILED: FindingSpec(NOTE, "masses and COMs could not be fused with the prior: {error}"),
    C.PAPER_SPLIT_ARBITRARY: FindingSpec(
        NOTE, "paper method: m2 and m3 are not identifiable from gravity; the bounded solver's split is arbitrary"
    ),
    C.PAPER_STD_CLASSICAL: FindingSpec(
        NOTE, "paper method: std are classical per-joint errors, ignoring errors carried down the chain"
    ),
    C.DATA_NOTE: FindingSpec(NOTE, _DETAIL),
    C.BAG_NOTE: FindingSpec(NOTE, _DETAIL),
    C.BAG_DAMAGED: FindingSpec(NOTE, _bag_damaged, "the recording is damaged", "check the recording's storage"),
    C.BAG_POSSIBLY_DAMAGED: FindingSpec(NOTE, _possibly_damaged),
    C.TIMING_NOTE: FindingSpec(NOTE, _DETAIL),
    C.TARE_NOTE: FindingSpec(NOTE, _DETAIL),
    C.PRIOR_NOTE: FindingSpec(NOTE, _DETAIL),
}

assert set(SPECS) == set(FindingCode), "every finding code needs its spec"
