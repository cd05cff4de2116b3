"""Invalid estimates as the identifier publishes them (its inputs waiting or stale, its data not yet enough)."""

from __future__ import annotations

from typing import Any

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.methods import Method

WAITING = Finding(code=FindingCode.INPUT_WAITING, values={"what": "wrench"})
STALE = Finding(code=FindingCode.INPUT_STALE, values={"what": "wrench", "silent_s": 0.5})
POOR = Finding(code=FindingCode.NOT_YET_DETERMINED)
NOT_IDENTIFIED = Finding(code=FindingCode.NOT_IDENTIFIABLE, values={"condition": 2e9})
ONE_WAY_ELBOW = Finding(code=FindingCode.ONE_DIRECTION, where="elbow", values={"other_percent": 0.0})
ONE_WAY_WRIST = Finding(code=FindingCode.ONE_DIRECTION, where="wrist", values={"other_percent": 0.0})


def invalid(finding: Finding = STALE) -> dict[str, Any]:
    """The document of an invalid estimate made so by ``finding`` (``STALE``: the identifier's inputs stopped)."""
    return Estimate.invalid(Method.JOINT, finding).to_json()
