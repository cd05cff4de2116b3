"""Identify a recorded bag: read it, identify, and attach what the read found to the estimate."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from bsp_ros.bag import TopicMap, read_session
from bsp_ros.bag.fingerprint import content_sha256, recordings_sha256
from bsp_ros.bag.reader import BagRead
from bsp_ros.core.estimate_blocks import BagSection
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding, FindingCode, note
from bsp_ros.core.pipeline import IdentifyOptions, estimate_recordings


def identify_bag(
    path: str | Path,
    options: IdentifyOptions | None = None,
    topics: TopicMap | None = None,
    progress: Callable[[int, int], None] | None = None,
    sha256: str | None = None,
) -> dict[str, Any]:
    """The docs/contract.md estimate of a rosbag2 MCAP bag, with a ``bag`` section on what was read and lost.

    Damage (CRC errors, truncation) does not stop the identification of what is intact; it is reported in
    ``bag`` and as a warning in ``quality.warnings``. ``sha256``: the bag's :func:`content_sha256` if the
    caller has it already (else it is computed here).

    Raises
    ------
    BspError
        The bag is missing, not a bag, empty, lacks a required topic or carries a wrong type.
    """
    return estimate_from_read(read_session(path, topics=topics, progress=progress), path, options, sha256)


def estimate_from_read(
    read: BagRead, path: str | Path, options: IdentifyOptions | None = None, sha256: str | None = None
) -> dict[str, Any]:
    """:func:`identify_bag` on a bag already read (``read_session`` of ``path``): a caller that needs the streams
    too (the session store's within-session cycles) reads the bag once."""
    return typed_estimate_from_read(read, path, options, sha256).to_json()


def typed_estimate_from_read(
    read: BagRead, path: str | Path, options: IdentifyOptions | None = None, sha256: str | None = None
) -> Estimate:
    """The typed estimate of a bag already read (``read_session`` of ``path``), with what the read found."""
    # The content hash lets the session store refuse this recording's result JSON once the bag is stored.
    info = {"source": Path(path).name, "content_sha256": sha256 or content_sha256(path)}
    return with_read(estimate_recordings([read.session], options, session_info=info), read)


def with_read(estimate: Estimate, read: BagRead, recording: int | None = None) -> Estimate:
    """``estimate`` with what the read of one bag found (damage, the rotation's source, implausible samples): its
    ``bag`` section (appended to ``bags`` for ``recording`` k of several) and the findings."""
    report = read.report

    def in_recording(finding: Finding) -> Finding:
        return finding if recording is None else finding.in_recording(recording + 1)

    quality = estimate.quality
    if report.damaged:
        values = {
            "crc_errors": report.crc_errors,
            "truncated": bool(report.truncated),
            "lost_messages": report.lost_messages,
        }
        quality = quality.with_finding(in_recording(Finding(code=FindingCode.BAG_DAMAGED, values=values)), at=0)
    at = 1
    for text in report.warnings:
        finding = in_recording(note(FindingCode.BAG_NOTE, text))
        if finding.text not in quality.warnings:
            quality = quality.with_finding(finding, at=at)
            at += 1
    if quality.rotation is not None:  # where the bag's sensor orientation came from (the pipeline knows its shape)
        rotation = quality.rotation.with_source(report.rotation_source, appended=bool(recording))
        quality = quality.with_rotation(rotation)
    if report.rotation_source == "assumed" and not quality.valid:
        frame = read.session.wrench.frame_id
        quality = quality.with_finding(Finding(code=FindingCode.ROTATION_ASSUMED, values={"frame": frame}))
    # Samples implausible in themselves (not merely off the model's fit): the signature of bit damage.
    removed = quality.extra.get("removed_samples", {})
    implausible = {k: v for k, v in removed.items() if k.startswith(("wrench", "marker"))}
    if report.chunks_without_crc and implausible:
        # Without chunk CRCs, bit damage shows only as implausible values: say how many were removed.
        possibly = Finding(
            code=FindingCode.BAG_POSSIBLY_DAMAGED, values={"implausible": tuple((k, v) for k, v in implausible.items())}
        )
        quality = quality.with_finding(in_recording(possibly), at=0)
    section = BagSection(
        files=tuple(Path(f).name for f in report.files),
        messages={topic: t.read for topic, t in report.topics.items()},
        lost_messages=report.lost_messages,
        crc_errors=report.crc_errors,
        truncated=report.truncated,
        chunks_without_crc=report.chunks_without_crc,
        rotation_source=report.rotation_source,
        damage=tuple(report.damage),
        implausible_samples_removed=implausible,
    )
    return estimate.with_quality(quality).with_bag(section, recording=recording)


def identify_bags(
    paths: Sequence[str | Path],
    options: IdentifyOptions | None = None,
    topics: TopicMap | None = None,
    progress: Callable[[int, int], None] | None = None,
    trunk_tilts_rad: Sequence[float] | None = None,
) -> dict[str, Any]:
    """The document of :func:`estimate_bags` (its ``to_json()``)."""
    return estimate_bags(paths, options, topics, progress, trunk_tilts_rad).to_json()


def estimate_bags(
    paths: Sequence[str | Path],
    options: IdentifyOptions | None = None,
    topics: TopicMap | None = None,
    progress: Callable[[int, int], None] | None = None,
    trunk_tilts_rad: Sequence[float] | None = None,
) -> Estimate:
    """The estimate of one arm from several recordings (bags) identified together, each with its trunk's tilt
    (:func:`bsp_ros.core.pipeline.estimate_recordings`); one bag without a tilt is :func:`identify_bag`'s.

    The estimate's ``session.source`` joins the bags' names, ``session.content_sha256`` hashes their hashes in
    order, ``session.recordings`` lists each, and ``bags`` holds each bag's ``bag`` section.

    Raises
    ------
    BspError
        Any bag fails as in :func:`identify_bag`; InputError for recordings that are not of one arm.
    """
    if len(paths) == 1 and not any(trunk_tilts_rad or ()):
        return typed_estimate_from_read(read_session(paths[0], topics=topics, progress=progress), paths[0], options)
    reads = [read_session(path, topics=topics, progress=progress) for path in paths]
    return typed_estimate_from_reads(reads, paths, options, trunk_tilts_rad)


def estimate_from_reads(
    reads: Sequence[BagRead],
    paths: Sequence[str | Path],
    options: IdentifyOptions | None = None,
    trunk_tilts_rad: Sequence[float] | None = None,
) -> dict[str, Any]:
    """:func:`identify_bags` of recordings already read (``reads[k]`` of ``paths[k]``)."""
    return typed_estimate_from_reads(reads, paths, options, trunk_tilts_rad).to_json()


def typed_estimate_from_reads(
    reads: Sequence[BagRead],
    paths: Sequence[str | Path],
    options: IdentifyOptions | None = None,
    trunk_tilts_rad: Sequence[float] | None = None,
) -> Estimate:
    """:func:`estimate_bags` of recordings already read (``reads[k]`` of ``paths[k]``)."""
    combined, hashes = recordings_sha256(paths)
    info = {"source": " + ".join(Path(path).name for path in paths), "content_sha256": combined}
    recordings = [{"source": Path(path).name, "content_sha256": sha} for path, sha in zip(paths, hashes, strict=True)]
    estimate = estimate_recordings([r.session for r in reads], options, trunk_tilts_rad, info, recordings)
    for k, read in enumerate(reads):
        estimate = with_read(estimate, read, k)
    return estimate
