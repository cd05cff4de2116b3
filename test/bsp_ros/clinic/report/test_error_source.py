"""The report's sentence on measurement error names the agreement (ICC) of the quantities it judges, in words."""

from __future__ import annotations

import numpy as np

from bsp_ros.clinic.mdc import pooled_error
from bsp_ros.clinic.report.analysis import Series
from bsp_ros.clinic.report.summary import error_source


class _Analysis:
    def __init__(self, series: tuple[Series, ...]) -> None:
        self.series = series


def _series(joint: str, noise: float, seed: int) -> Series:
    rng = np.random.default_rng(seed)
    level = rng.uniform(0.3, 0.9, 8)  # 8 subjects, each once retested
    pairs = [
        (a + noise * rng.standard_normal(), a + noise * rng.standard_normal(), f"S{i}") for i, a in enumerate(level)
    ]
    return Series(
        arm=None,
        key=("joints", joint, "coulomb_nm"),
        label=joint,
        unit="Nm",
        points=(),
        error=pooled_error(pairs, "cell"),
        judged=True,
    )


def test_two_judged_quantities_give_the_range_of_their_agreement() -> None:
    close, loose = _series("elbow", 0.01, 1), _series("shoulder", 0.2, 2)
    assert close.error.icc is not None and loose.error.icc is not None
    assert close.error.icc > 0.9 > loose.error.icc  # the truth: one agrees well, the other poorly
    sentence = error_source(_Analysis((close, loose)))
    assert (
        f"(ICC) from {loose.error.icc:.2f} (shoulder friction, poor) to {close.error.icc:.2f} (elbow friction, "
        "excellent) over the 2 quantities judged"
    ) in sentence


def test_one_judged_quantity_names_its_agreement() -> None:
    only = _series("elbow", 0.05, 3)
    sentence = error_source(_Analysis((only,)))
    assert only.error.icc is not None
    word = "excellent" if only.error.icc >= 0.9 else "good" if only.error.icc >= 0.75 else "moderate"
    assert f"{word} agreement between patients' tests and retests (ICC {only.error.icc:.2f}) for elbow friction" in (
        sentence
    )
