"""Where the data reject the fixed passive model: the elastic family the data choose from, fitted instead."""

from __future__ import annotations

import dataclasses

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.passive import AUTO
from bsp_ros.core.identification.result import IdentificationResult

__all__ = ["elastic_family_fit", "family_result"]


def family_result(data: IdentificationData, config: JointConfig) -> IdentificationResult:
    """``data`` identified with the elastic family the data choose from (``--passive auto``) in place of ``config``'s
    fixed passive model, and no further fallback."""
    from bsp_ros.core.identification.joint.identify import identify_joint  # the whole identification, once more

    chosen = dataclasses.replace(config.passive, select=True)
    return identify_joint(data, dataclasses.replace(config, passive=chosen, elastic_fallback=False))


def elastic_family_fit(
    data: IdentificationData, config: JointConfig, misfits: list[Finding]
) -> IdentificationResult | None:
    """Where the fixed passive model does not fit (``misfits``: per joint; nothing else is wrong), the elastic
    family the data choose from (``--passive auto``), if it fits and is valid; None otherwise.

    A spring the fixed model lacks leaves a residual far above the sensor noise: the elastic check, which would
    find it, runs only on a model that fits. On a MuJoCo arm with joint springs and a planned trajectory the
    default model was invalid here ("does not fit at the wrist", static moments 4.7 std off) while the family was
    valid within 1.5 std (bench/README.md, physics engine). A misfit the family cannot take up (a wrong sensor
    transform, a load, low-speed friction) leaves it invalid too, and the fixed model's verdict stands.
    """
    if "offset" in config.passive.terms:  # an elastic model already: nothing wider to choose from
        return None
    family = family_result(data, config)
    if not family.valid:
        return None
    values = {
        "model": config.passive.label,
        "passive_option": AUTO,  # the `--passive` model whose choice the estimate uses
        "joints": tuple(f.where for f in misfits),
        **{key: tuple(float(f.values[key]) for f in misfits) for key in ("rms_nm", "ratio", "noise_nm")},
    }
    return family.with_findings(Finding(code=FindingCode.ELASTIC_FAMILY_CHOSEN, values=values), first=True)
