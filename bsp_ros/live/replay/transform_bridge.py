"""A bag's /tf_static and /tf replayed where tf2_msgs is not installed: the sensor frame's rotation goes out as
geometry_msgs/TransformStamped on the cell's transform topic, which `bsp_identifier` reads without tf2_msgs."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bsp_ros.bag.cdr import decode_tf_message
from bsp_ros.bag.reader.rotation import usable_transform
from msg_adapters.rotation import quaternion_from_matrix
from msg_adapters.rotation_track import TransformBuffer
from msg_adapters.tf import TransformSample

__all__ = ["TransformBridge"]


class TransformBridge:
    """Composes the ``world_frame -> sensor_frame`` chain of the TF messages fed to it and publishes it.

    Parameters
    ----------
    world_frame, sensor_frame : the chain's ends (the cell's).
    publish : sends one transform (the player's TransformStamped writer).

    Attributes
    ----------
    sent : transforms published.
    undecodable : TF messages whose bytes were not a TFMessage.
    """

    def __init__(self, world_frame: str, sensor_frame: str, publish: Callable[[TransformSample], None]) -> None:
        self.world_frame = world_frame
        self.sensor_frame = sensor_frame
        self.publish = publish
        self.buffer = TransformBuffer()
        self.sent = 0
        self.undecodable = 0

    def writer(self, static: bool) -> Callable[[bytes], None]:
        """What plays one serialized TFMessage of /tf_static (``static``) or /tf: the chain at its newest stamp,
        once it connects the sensor frame to world."""

        def write(data: bytes) -> None:
            samples = decode_tf_message(data)
            if samples is None:
                self.undecodable += 1
                return
            usable = [s for s in samples if usable_transform(s)]
            if not usable:
                return
            (self.buffer.add_static if static else self.buffer.add)(usable)
            stamp = max(s.t_ns for s in usable)
            track = self.buffer.track(self.world_frame, self.sensor_frame, [stamp])
            if track is None:
                return
            quaternion = quaternion_from_matrix(track.rotations[0])
            self.publish(TransformSample(stamp, self.world_frame, self.sensor_frame, np.zeros(3), quaternion))
            self.sent += 1

        return write
