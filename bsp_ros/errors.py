"""The bsp_ros exception hierarchy: one base, a few kinds, messages that name the bad value."""


class BspError(Exception):
    """Base class of every error bsp_ros raises on purpose."""

    exit_code = 1


class InputError(BspError, ValueError):
    """A value given to bsp_ros is invalid (non-finite, out of range, wrong shape or type)."""

    exit_code = 2


class DataError(BspError):
    """Recorded or streamed data cannot be used (missing topic, too few samples, no motion)."""

    exit_code = 3


class BagError(BspError):
    """A bag cannot be read or written (missing, corrupt, truncated beyond use, wrong types)."""

    exit_code = 4


class StoreError(BspError):
    """The session store refuses an operation (unknown subject, duplicate, foreign schema)."""

    exit_code = 5


class RuntimeBackendError(BspError):
    """The middleware (rclpy) cannot be started or used."""

    exit_code = 6
