"""Both arms of one subject (affected and not) side by side: each arm's own series, headline and session list."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bsp_ros.cli import main
from bsp_ros.clinic.report import analyse
from bsp_ros.clinic.store import SubjectRecord, open_store
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate

DAY_NS = 86_400 * 10**9
SUBJECT = "T2"
# Elbow friction per visit (Nm): the affected left arm falls, the right one stays; retests on every visit day.
FRICTION = {"left": [0.8, 0.8, 0.4, 0.4], "right": [0.3, 0.3, 0.3, 0.3]}


def _estimate(seed: int, day: int, hour: int, friction_nm: float) -> dict:
    estimate = sample_estimate(seed, start_time_ns=SAMPLE_START_NS + day * DAY_NS + hour * 3600 * 10**9)
    estimate["joints"]["elbow"]["coulomb_nm"].update(value=friction_nm, std=0.005)
    return estimate


@pytest.fixture(scope="module")
def store_path(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("two_arms") / "clinic.sqlite"
    with open_store(path) as store:
        store.set_subject(SubjectRecord(SUBJECT, 70.0, 1.72, "male", "left", "left"))
        for k, (arm, plan) in enumerate(FRICTION.items()):
            for visit, friction in enumerate(plan):
                day, seed = 7 * visit, 100 * k + visit
                # The arms are measured one after the other on the same day; each visit has a retest an hour later
                # that differs by 0.01 Nm (alternating sign): the day-to-day error.
                store.add_estimate(_estimate(seed, day, 2 * k, friction), SUBJECT, arm=arm)
                retest = friction + (0.01 if visit % 2 else -0.01)
                store.add_estimate(_estimate(seed + 50, day, 2 * k + 1, retest), SUBJECT, arm=arm, retest=True)
    return path


def test_each_arm_is_analysed_on_its_own(store_path: Path) -> None:
    with open_store(store_path) as store:
        analysis = analyse(
            SUBJECT, store.sessions(SUBJECT), pool=store.sessions(), subject_record=store.subject_record(SUBJECT)
        )
    assert analysis.arms == ("left", "right")  # the recorded (affected) arm first
    flagged = {s.arm for s in analysis.series if s.key == ("joints", "elbow", "coulomb_nm") and s.changes}
    assert flagged == {"left"}  # the fall of the affected arm, nothing on the unchanged one
    assert len(analysis.visits("left")) == 4 and len(analysis.visits("right")) == 4


def test_the_report_puts_both_arms_side_by_side(store_path: Path, tmp_path: Path) -> None:
    html = tmp_path / "report.html"
    assert main(["report", SUBJECT, "--out", str(html), "--store", str(store_path)]) == 0
    first_page = html.read_text(encoding="utf-8").split("<section id='first-page'>")[1].split("</section>")[0]
    text = re.sub(r"<[^>]+>", " ", first_page)
    left, right = text.index("Left arm (affected)"), text.index("Right arm")
    assert left < right
    # Each arm's headline under its own title: the fall under the left arm, no change under the right.
    assert "fell 50 %" in text[left:right] and "Right arm (unaffected)" in text
    assert " ".join(text[right:].split()).startswith("Right arm (unaffected) No change beyond measurement error")
