"""Store round trips on SQLite and PostgreSQL: add, list, show, erase, duplicates and bad input."""

from __future__ import annotations

import io

import pytest

from bsp_ros.clinic.store import SessionRecord, SubjectRecord, open_store, parse_estimate, write_sessions_csv
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate
from bsp_ros.errors import InputError, StoreError

DAY_NS = 86_400 * 10**9


def _times(records: list[SessionRecord]) -> list[int]:
    return [r.session_time_ns for r in records]


def test_round_trip_keeps_every_quantity(store_location: str) -> None:
    estimate = sample_estimate(3, config={"passive_model": "coulomb", "window_s": 2.5})
    with open_store(store_location) as store:
        stored = store.add_estimate(estimate, "S01")
        assert stored.id is not None and stored.added_ns is not None
    with open_store(store_location) as store:  # a new connection: what was acknowledged is there
        (back,) = store.sessions("S01")
    assert back.subject == "S01" and back.session_time_ns == SAMPLE_START_NS
    assert back.source == "session.mcap" and back.method == "static-ols"
    assert back.config == {"passive_model": "coulomb", "window_s": 2.5}
    assert back.quality == stored.quality and back.quality.valid
    assert back.parameters == stored.parameters
    forearm = estimate["segments"]["forearm"]["static_moment_kgm"]
    q = back.parameters[("segments", "forearm", "static_moment_kgm")]
    assert (q.value, q.std, q.source) == (forearm["value"], forearm["std"], "data")
    assert len(back.parameters) == 3 * 5 + 3


def test_two_segment_and_new_quantities_need_no_migration(store_location: str) -> None:
    extra = {("joints", "elbow", "viscous_nms"): (0.02, 0.004), ("joints", "elbow", "stiffness_nm_per_rad"): (0.5, 0.1)}
    estimate = sample_estimate(1, segments=("upper_arm", "forearm"), overrides=extra)
    with open_store(store_location) as store:
        store.add_estimate(estimate, "arm-2seg")
        (back,) = store.sessions("arm-2seg")
    assert {part for _, part, _ in back.parameters} == {"upper_arm", "forearm", "shoulder", "elbow"}
    assert back.parameters[("joints", "elbow", "viscous_nms")].value == 0.02
    assert back.parameters[("joints", "elbow", "stiffness_nm_per_rad")].std == 0.1


def test_list_show_and_erase_one_subject(store_location: str) -> None:
    with open_store(store_location) as store:
        for day in (2, 0, 1):
            store.add_estimate(sample_estimate(day, start_time_ns=SAMPLE_START_NS + day * DAY_NS), "A1")
        store.add_estimate(sample_estimate(9, valid=False, warnings=["too little motion"]), "B2")
        summary = {s.subject: s for s in store.subjects()}
        assert (summary["A1"].n_sessions, summary["B2"].n_sessions, summary["B2"].n_invalid) == (3, 1, 1)
        assert _times(store.sessions("A1")) == [SAMPLE_START_NS + d * DAY_NS for d in range(3)]
        assert store.sessions("B2")[0].quality.warnings == ("too little motion",)
        assert store.erase("A1") == 3
        assert [s.subject for s in store.subjects()] == ["B2"]
        with pytest.raises(StoreError, match="unknown subject A1"):
            store.sessions("A1")
        with pytest.raises(StoreError, match="unknown subject A1"):
            store.erase("A1")
        assert len(store.sessions()) == 1


def test_duplicate_session_is_refused_and_nothing_lost(store_location: str) -> None:
    with open_store(store_location) as store:
        first = store.add_estimate(sample_estimate(1), "S01")
        with pytest.raises(StoreError, match="duplicate session"):
            store.add_estimate(sample_estimate(2), "S01")  # same subject, time and source; other values
        store.add_estimate(sample_estimate(3, source="other.mcap"), "S01")  # another recording: fine
        store.add_estimate(sample_estimate(4), "S02")  # another subject: fine
        kept = store.sessions("S01")
    assert [r.source for r in kept] == ["session.mcap", "other.mcap"]
    assert kept[0].parameters == first.parameters


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda e: e.pop("schema"), "foreign JSON"),
        (lambda e: e.update(schema="bsp_ros/core/estimate/9"), "unsupported estimate schema"),
        (lambda e: e.pop("quality"), "'quality' must be an object"),
        (lambda e: e["quality"].update(valid="yes"), "quality.valid"),
        (lambda e: e["segments"]["forearm"]["mass_kg"].update(source="guess"), "source must be one of"),
        (lambda e: e["segments"]["forearm"]["mass_kg"].update(value="1.2"), "must be a number"),
        (lambda e: e["segments"]["forearm"]["mass_kg"].update(std=-1.0), "must not be negative"),
        (lambda e: e["joints"].update(elbow=[1, 2]), "must be an object"),
        (lambda e: e["session"].pop("start_time_ns"), "no session.start_time_ns"),
        (lambda e: e["session"].update(start_time_ns=1_717_225_200), "not a wall-clock time"),
    ],
)
def test_bad_estimates_are_refused_and_nothing_lost(store_location: str, mutate: object, message: str) -> None:
    with open_store(store_location) as store:
        store.add_estimate(sample_estimate(1), "S01")
        bad = sample_estimate(2, source="bad.mcap")
        mutate(bad)  # type: ignore[operator]
        with pytest.raises((StoreError, InputError), match=message):
            store.add_estimate(bad, "S01")
        assert len(store.sessions("S01")) == 1


@pytest.mark.parametrize("subject", ["", "   ", "x" * 65, "Jane Doe", "jane.doe@example.org", "a/b", "S01\n"])
def test_subject_ids_must_be_pseudonyms(store_location: str, subject: str) -> None:
    with open_store(store_location) as store, pytest.raises(InputError, match="subject id"):
        store.add_estimate(sample_estimate(1), subject)


def test_non_finite_values_are_stored_as_missing(store_location: str) -> None:
    estimate = sample_estimate(1, valid=False, overrides={("joints", "elbow", "coulomb_nm"): (float("nan"), None)})
    estimate["quality"]["condition_number"] = float("inf")
    with open_store(store_location) as store:
        store.add_estimate(estimate, "S01")
        (back,) = store.sessions("S01")
    q = back.parameters[("joints", "elbow", "coulomb_nm")]
    assert (q.value, q.std) == (None, None) and back.quality.condition_number is None


def test_subject_block_keeps_only_anthropometrics(store_location: str) -> None:
    estimate = sample_estimate(1, subject={"body_mass_kg": 72.5, "sex": "female", "name": "Jane Doe"})
    with open_store(store_location) as store:
        store.add_estimate(estimate, "S01")
        (back,) = store.sessions("S01")
    assert back.subject_info == {"body_mass_kg": 72.5, "sex": "female"}
    with pytest.raises(InputError, match="body mass"):
        parse_estimate(sample_estimate(1, subject={"body_mass_kg": 7.0}), "S01")


def test_a_session_keeps_the_body_data_its_prior_was_made_with(store_location: str) -> None:
    made_with = {"body_mass_kg": 75.0, "height_m": 1.78, "sex": "male"}
    with open_store(store_location) as store:
        store.set_subject(SubjectRecord("S01", 68.0, 1.65, "female", "left"))
        stored = store.add_estimate(sample_estimate(1, subject=made_with), "S01")
        (back,) = store.sessions("S01")
        known = store.subject_record("S01")
    # Not the record's female 68 kg: the masses were fused with the male 75 kg table.
    assert back.subject_info == stored.subject_info == made_with and back.arm == "left"
    assert known is not None and known.differs_from(back.subject_info)
    assert not known.differs_from({"body_mass_kg": 68, "height_m": 1.65, "sex": "female"})
    assert known.identify_options() == "--body-mass 68 --height 1.65 --sex female"


def test_csv_export(store_location: str) -> None:
    with open_store(store_location) as store:
        store.add_estimate(sample_estimate(1), "S01")
        store.add_estimate(sample_estimate(2, segments=("upper_arm", "forearm")), "S02")
        stream = io.StringIO()
        rows = write_sessions_csv(store.sessions(), stream)
    lines = stream.getvalue().splitlines()
    assert rows == 18 + 12 == len(lines) - 1
    assert lines[0].startswith("subject,session_time_utc,session_time_ns,session_source")
    assert any(line.startswith("S02,2024-06-01T07:00:00Z,") and ",joints,elbow,coulomb_nm," in line for line in lines)


def test_report_analysis_reads_either_backend(store_location: str) -> None:
    from bsp_ros.clinic.report import analyse

    planted = {("joints", "elbow", "coulomb_nm"): (0.9, 0.03)}
    with open_store(store_location) as store:
        for day in range(6):
            estimate = sample_estimate(
                day,
                start_time_ns=SAMPLE_START_NS + day * DAY_NS,
                overrides=planted if day == 5 else None,
                sem_rel=0.05,  # a within-session SEM: it never judges a change
            )
            store.add_estimate(estimate, "R1")
        assert analyse("R1", store.sessions("R1")).changes == []
        for day in range(5):
            retest = sample_estimate(100 + day, start_time_ns=SAMPLE_START_NS + day * DAY_NS + 3_600 * 10**9)
            store.add_estimate(retest, "R1", retest=True)
        analysis = analyse("R1", store.sessions("R1"))
    # The planted step at the latest session is a possible change, to be confirmed by the next session.
    assert analysis.changes == []
    assert [(c.key, c.after.time_ns) for c in analysis.possible_changes] == [
        (("joints", "elbow", "coulomb_nm"), SAMPLE_START_NS + 5 * DAY_NS)
    ]
