"""What a playback did: messages published per topic, topics skipped, damage found, acknowledgement."""

from __future__ import annotations

from dataclasses import dataclass, field

from bsp_ros.bag.mcap_scan import ScanResult
from bsp_ros.cell import CellDescription


@dataclass(kw_only=True)
class PlayReport:
    """What a playback did.

    Attributes
    ----------
    path : the bag played.
    published : topic -> messages published (over all loops).
    expected : topic -> messages the bag lists per pass (None if unknown).
    skipped : topic -> why it was not played (unknown type, not CDR, not selected).
    bridged : TF topic -> the TransformStamped topic its sensor rotation went out on (tf2_msgs not installed).
    bridge_sent : TransformStamped messages the bridged TF topics gave.
    matched : topic -> matched subscriptions when playback started.
    loops : complete passes over the bag.
    crc_errors, truncated : damage found in the (first) pass.
    lost_in_bad_chunks : topic -> messages in chunks that failed their CRC.
    damage : one line per damaged place.
    first_pass : topic -> messages published by the first complete pass (empty if none completed).
    acked : every reliable writer's samples were acknowledged at the end (None: nothing to wait for).
    interrupted : playback was stopped before the end.
    wall_s : playback time, s.
    """

    path: str
    published: dict[str, int] = field(default_factory=dict)
    expected: dict[str, int | None] = field(default_factory=dict)
    skipped: dict[str, str] = field(default_factory=dict)
    bridged: dict[str, str] = field(default_factory=dict)
    bridge_sent: int = 0
    matched: dict[str, int] = field(default_factory=dict)
    loops: int = 0
    first_pass: dict[str, int] = field(default_factory=dict)
    crc_errors: int = 0
    truncated: bool = False
    lost_in_bad_chunks: dict[str, int] = field(default_factory=dict)
    damage: list[str] = field(default_factory=list)
    acked: bool | None = None
    interrupted: bool = False
    wall_s: float = 0.0

    @property
    def damaged(self) -> bool:
        """True if part of the bag could not be read."""
        return bool(self.crc_errors or self.truncated or self.damage)

    def lost(self, topic: str) -> int | None:
        """Messages of ``topic`` the bag lists but a pass could not play (None if unknown)."""
        expected = self.expected.get(topic)
        if expected is not None and self.first_pass:
            return max(0, expected - self.first_pass.get(topic, 0))
        if self.damaged and topic in self.lost_in_bad_chunks:
            return self.lost_in_bad_chunks[topic]
        return None

    def summary_lines(self) -> list[str]:
        """Human-readable summary: one line per topic, then damage."""
        lines = []
        for topic in sorted(set(self.published) | set(self.expected)):
            if topic in self.skipped:
                continue
            count = self.published.get(topic, 0)
            expected = self.expected.get(topic)
            bridged = self.bridged.get(topic)
            text = f"{topic}: {count} {'played as its sensor rotation' if bridged else 'published'}"
            if expected is not None:
                text += f" (bag lists {expected}{' per pass' if self.loops > 1 else ''})"
            lost = self.lost(topic)
            if lost:
                text += f", {lost} lost to damage"
            lines.append(text)
        if self.bridged:
            lines.append(
                f"{', '.join(sorted(self.bridged))}: tf2_msgs is not installed; the sensor's rotation went out as "
                f"{self.bridge_sent} geometry_msgs/TransformStamped on {', '.join(sorted(set(self.bridged.values())))}"
            )
        for topic, why in sorted(self.skipped.items()):
            lines.append(f"{topic}: skipped ({why})")
        if self.damaged:
            lines.append(
                f"bag damaged: {self.crc_errors} chunks failed their CRC"
                + (", file truncated" if self.truncated else "")
                + "; the intact part was played"
            )
            lines += [f"  {line}" for line in self.damage]
        if self.acked is False:
            lines.append("not every reliable subscriber acknowledged all messages before the timeout")
        return lines


def dropped_for_nodes(report: PlayReport, cell: CellDescription) -> list[str]:
    """What the nodes need that the playback dropped: a skipped wrench, marker, handle pose, transform or TF topic,
    or TF topics that gave no rotation of the cell's sensor frame."""
    needed = {cell.wrench_topic, cell.transform_topic, cell.handle_pose_topic, "/tf_static", "/tf"} - {""}
    out = [
        f"{topic} ({why})"
        for topic, why in sorted(report.skipped.items())
        if topic in needed or topic.startswith(cell.marker_topic_prefix)
    ]
    if report.bridged and report.bridge_sent == 0 and any(report.published.get(t) for t in report.bridged):
        out.append(
            f"the sensor's rotation ({', '.join(sorted(report.bridged))} hold no transform "
            f"{cell.world_frame} -> {cell.sensor_frame})"
        )
    return out


def note_damage(report: PlayReport, scan: ScanResult) -> None:
    """Add the damage one file's scan found to ``report``."""
    report.crc_errors += scan.crc_errors
    report.truncated = report.truncated or scan.truncated
    report.damage.extend(scan.damage)
    for topic, count in scan.lost_in_bad_chunks.items():
        report.lost_in_bad_chunks[topic] = report.lost_in_bad_chunks.get(topic, 0) + count
    if scan.orphans:
        report.damage.append(f"{scan.orphans} messages on channels whose definition was lost (not played)")
