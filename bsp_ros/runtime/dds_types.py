"""Cyclone DDS ``IdlStruct`` classes generated from the ROS 2 Jazzy message definitions in rosbags."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import numpy as np
from cyclonedds.idl import IdlStruct, make_idl_struct
from cyclonedds.idl import types as idl
from rosbags.interfaces import Nodetype
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from bsp_ros.errors import RuntimeBackendError

__all__ = [
    "SUPPORTED_TYPES",
    "dds_class",
    "dds_to_ros",
    "dds_type_name",
    "message_class",
    "plain_sequences",
    "ros_to_dds",
    "type_hash",
    "typestore",
]

#: The message types the bsp_ros nodes use; any other type of the Jazzy typestore works as well.
SUPPORTED_TYPES: tuple[str, ...] = (
    "geometry_msgs/msg/WrenchStamped",
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/InertiaStamped",
    "geometry_msgs/msg/TransformStamped",
    "tf2_msgs/msg/TFMessage",
    "sensor_msgs/msg/JointState",
    "diagnostic_msgs/msg/DiagnosticArray",
    "std_msgs/msg/String",
    "rosgraph_msgs/msg/Clock",
    "rmw_dds_common/msg/ParticipantEntitiesInfo",
)

# rmw_dds_common/msg/ParticipantEntitiesInfo and its parts as in rmw_dds_common (Jazzy), used only if the
# typestore lacks them (rosbags 0.11 ships them).
_RMW_DDS_COMMON_MSGS: dict[str, str] = {
    "rmw_dds_common/msg/Gid": "char[16] data\n",
    "rmw_dds_common/msg/NodeEntitiesInfo": (
        "string<=256 node_namespace\nstring<=256 node_name\n"
        "rmw_dds_common/Gid[] reader_gid_seq\nrmw_dds_common/Gid[] writer_gid_seq\n"
    ),
    "rmw_dds_common/msg/ParticipantEntitiesInfo": (
        "rmw_dds_common/Gid gid\nrmw_dds_common/NodeEntitiesInfo[] node_entities_info_seq\n"
    ),
}

# ROS base type -> (IDL annotation for cyclonedds, numpy dtype or None for non-numeric).
# A ROS ``char`` is an IDL ``uint8`` and a ROS ``byte`` an IDL ``octet`` (rosidl_adapter's mapping);
# rosbags holds bytes as signed (int8), cyclonedds octets as unsigned (0..255).
_BASE: dict[str, tuple[Any, str | None]] = {
    "bool": (bool, "bool"),
    "byte": (idl.byte, "int8"),
    "char": (idl.uint8, "uint8"),
    "int8": (idl.int8, "int8"),
    "uint8": (idl.uint8, "uint8"),
    "int16": (idl.int16, "int16"),
    "uint16": (idl.uint16, "uint16"),
    "int32": (idl.int32, "int32"),
    "uint32": (idl.uint32, "uint32"),
    "int64": (idl.int64, "int64"),
    "uint64": (idl.uint64, "uint64"),
    "float32": (idl.float32, "float32"),
    "float64": (idl.float64, "float64"),
    "string": (str, None),
}

# cyclonedds' generic IDL helpers (indexable at run time, not typed as generics).
_ARRAY: Any = idl.array
_SEQUENCE: Any = idl.sequence
_BOUNDED_STR: Any = idl.bounded_str

_lock = threading.RLock()
_store: Typestore | None = None
_classes: dict[str, type[Any]] = {}
_to_dds: dict[str, Callable[[Any], Any]] = {}
_to_ros: dict[str, Callable[[Any], Any]] = {}
_plain: dict[str, Callable[[Any], Any] | None] = {}


def typestore() -> Typestore:
    """Return the rosbags ROS 2 Jazzy typestore, with the rmw_dds_common messages registered.

    Returns
    -------
    Typestore
        The process-wide typestore (created on first use).
    """
    global _store
    with _lock:
        if _store is None:
            from rosbags.typesys import get_types_from_msg

            store = get_typestore(Stores.ROS2_JAZZY)
            missing: dict[str, Any] = {}
            for name, text in _RMW_DDS_COMMON_MSGS.items():
                if name not in store.fielddefs:
                    missing.update(get_types_from_msg(text, name))
            if missing:
                store.register(missing)
            _store = store
        return _store


def _fielddefs(type_name: str) -> list[tuple[str, Any]]:
    store = typestore()
    if type_name not in store.fielddefs:
        raise RuntimeBackendError(f"unknown ROS message type {type_name!r} (not in the Jazzy typestore)")
    return list(store.fielddefs[type_name][1])


def dds_type_name(type_name: str) -> str:
    """Return the DDS type name ROS 2 uses on the wire for a message type.

    Parameters
    ----------
    type_name : str
        ROS type name such as ``"geometry_msgs/msg/WrenchStamped"``.

    Returns
    -------
    str
        ``"geometry_msgs::msg::dds_::WrenchStamped_"``.
    """
    parts = type_name.split("/")
    if len(parts) != 3 or not all(parts):
        raise RuntimeBackendError(f"ROS type name must look like pkg/msg/Type, got {type_name!r}")
    pkg, kind, name = parts
    return f"{pkg}::{kind}::dds_::{name}_"


def _base_annotation(base: str, str_bound: int) -> Any:
    if base not in _BASE:
        raise RuntimeBackendError(f"ROS base type {base!r} is not supported by the DDS runtime")
    if base == "string" and str_bound > 0:
        return _BOUNDED_STR[str_bound]
    return _BASE[base][0]


def _annotation(desc: Any) -> Any:
    kind = desc[0]
    if kind == Nodetype.BASE:
        return _base_annotation(*desc[1])
    if kind == Nodetype.NAME:
        return dds_class(desc[1])
    inner, size = desc[1]
    element = _annotation(inner)
    if kind == Nodetype.ARRAY:
        return _ARRAY[element, size]
    if size:
        return _SEQUENCE[element, size]
    return _SEQUENCE[element]


def dds_class(type_name: str) -> type[Any]:
    """Return (building on first use) the cyclonedds ``IdlStruct`` class of a ROS message type.

    The class is a dataclass: construct it by keyword with every field given. Field names are those of
    the ROS definition (as normalised by rosbags: a Python keyword gets a trailing underscore).

    Parameters
    ----------
    type_name : str
        ROS type name such as ``"geometry_msgs/msg/WrenchStamped"``.

    Returns
    -------
    type
        An ``IdlStruct`` subclass whose DDS type name is ``<pkg>::msg::dds_::<Type>_``.
    """
    with _lock:
        cls = _classes.get(type_name)
        if cls is None:
            fields = {name: _annotation(desc) for name, desc in _fielddefs(type_name)}
            class_name = type_name.replace("/", "__")
            built: Any = make_idl_struct(class_name, dds_type_name(type_name), fields)
            built.__ros_type__ = type_name
            _classes[type_name] = cls = built
        return cls


def message_class(type_name: str) -> type[Any]:
    """Return the rosbags Jazzy message class of a ROS type, the one the DDS runtime (de)serialises.

    Raises
    ------
    RuntimeBackendError
        If the type is unknown, naming it.
    """
    dds_class(type_name)  # an unknown type fails here, naming it
    cls: type[Any] = typestore().types[type_name]
    return cls


def type_hash(type_name: str) -> str:
    """Return the REP 2011 type hash ``RIHS01_<sha256 hex>`` of a ROS message type (computed by rosbags)."""
    _fielddefs(type_name)
    return str(typestore().hash_rihs01(type_name))


# --- conversion between rosbags messages and DDS objects, compiled once per type by field walking ---


def _numeric_dtype(desc: Any) -> str | None:
    if desc[0] == Nodetype.BASE:
        return _BASE.get(desc[1][0], (None, None))[1]
    return None


def _byte_to_dds(value: Any) -> int:
    # rosbags holds a scalar ROS byte as a signed int (-128..127), cyclonedds an octet as 0..255.
    return int(value) & 0xFF


def _byte_to_ros(value: Any) -> int:
    number = int(value)
    return number - 256 if number > 127 else number


def _element_to_dds(desc: Any) -> Callable[[Any], Any]:
    kind = desc[0]
    if kind == Nodetype.NAME:
        return _compile_to_dds(desc[1])
    if kind == Nodetype.BASE:
        base = desc[1][0]
        if base == "string":
            return str
        if base == "bool":
            return bool
        if base in ("float32", "float64"):
            return float
        if base == "byte":
            return _byte_to_dds
        return int
    inner = desc[1][0]
    if inner[0] == Nodetype.BASE and inner[1][0] in ("byte", "char", "uint8"):
        return lambda value: bytes(np.asarray(value).astype(np.uint8))
    if inner[0] == Nodetype.BASE and inner[1][0] != "string":
        return lambda value: np.asarray(value).tolist()
    convert = _element_to_dds(inner)
    return lambda value: [convert(item) for item in value]


def _compile_to_dds(type_name: str) -> Callable[[Any], Any]:
    with _lock:
        done = _to_dds.get(type_name)
        if done is not None:
            return done
        cls = dds_class(type_name)
        parts = [(name, _element_to_dds(desc)) for name, desc in _fielddefs(type_name)]

        def convert(msg: Any) -> Any:
            return cls(**{name: fn(getattr(msg, name)) for name, fn in parts})

        _to_dds[type_name] = convert
        return convert


def _element_to_ros(desc: Any) -> Callable[[Any], Any]:
    kind = desc[0]
    if kind == Nodetype.NAME:
        return _compile_to_ros(desc[1])
    if kind == Nodetype.BASE:
        base = desc[1][0]
        if base == "string":
            return str
        if base == "bool":
            return bool
        if base in ("float32", "float64"):
            return float
        if base == "byte":
            return _byte_to_ros
        return int
    inner = desc[1][0]
    dtype = _numeric_dtype(inner)
    if dtype is not None:
        if dtype in ("uint8", "int8") and inner[1][0] != "int8":
            return lambda value: np.frombuffer(bytes(value), dtype=dtype).copy()
        return lambda value: np.asarray(list(value), dtype=dtype)
    convert = _element_to_ros(inner)
    return lambda value: [convert(item) for item in value]


def _compile_to_ros(type_name: str) -> Callable[[Any], Any]:
    with _lock:
        done = _to_ros.get(type_name)
        if done is not None:
            return done
        cls = typestore().types[type_name]
        parts = [(name, _element_to_ros(desc)) for name, desc in _fielddefs(type_name)]

        def convert(obj: Any) -> Any:
            return cls(**{name: fn(getattr(obj, name)) for name, fn in parts})

        _to_ros[type_name] = convert
        return convert


def ros_to_dds(msg: Any, type_name: str | None = None) -> IdlStruct:
    """Convert a rosbags message object to the matching DDS object.

    Parameters
    ----------
    msg : object
        A rosbags message (a dataclass of the typestore, numeric arrays as numpy arrays).
    type_name : str, optional
        ROS type name; taken from ``msg.__msgtype__`` when omitted.

    Returns
    -------
    IdlStruct
        An instance of :func:`dds_class` ``(type_name)``.
    """
    name = type_name or getattr(msg, "__msgtype__", None)
    if not name:
        raise RuntimeBackendError(f"cannot tell the ROS type of {type(msg).__name__}: give type_name")
    result: IdlStruct = _compile_to_dds(name)(msg)
    return result


def dds_to_ros(obj: IdlStruct, type_name: str | None = None) -> Any:
    """Convert a DDS object of :func:`dds_class` to the rosbags message object.

    Parameters
    ----------
    obj : IdlStruct
        A DDS sample (numeric sequences as lists, ``uint8`` arrays as bytes).
    type_name : str, optional
        ROS type name; taken from the class when omitted.

    Returns
    -------
    object
        A rosbags message of the Jazzy typestore, numeric arrays as numpy arrays.
    """
    name = type_name or getattr(type(obj), "__ros_type__", None)
    if not name:
        raise RuntimeBackendError(f"cannot tell the ROS type of {type(obj).__name__}: give type_name")
    return _compile_to_ros(name)(obj)


def _each(fn: Callable[[Any], Any]) -> Callable[[Any], Any]:
    def each(values: Any) -> Any:
        out = [fn(item) for item in values]
        return values if all(a is b for a, b in zip(out, values, strict=True)) else out

    return each


def _compile_plain(type_name: str) -> Callable[[Any], Any] | None:
    with _lock:
        if type_name in _plain:
            return _plain[type_name]
        _plain[type_name] = None  # ROS messages cannot nest themselves; guards the recursion anyway
        parts: list[tuple[str, Callable[[Any], Any]]] = []
        for name, desc in _fielddefs(type_name):
            if desc[0] == Nodetype.NAME:
                inner_fn = _compile_plain(desc[1])
                if inner_fn is not None:
                    parts.append((name, inner_fn))
            elif desc[0] in (Nodetype.ARRAY, Nodetype.SEQUENCE):
                inner = desc[1][0]
                if inner[0] == Nodetype.NAME:
                    element_fn = _compile_plain(inner[1])
                    if element_fn is not None:
                        parts.append((name, _each(element_fn)))
                elif inner[1][0] in ("byte", "char", "uint8"):
                    parts.append((name, lambda v: bytes(v.astype(np.uint8)) if isinstance(v, np.ndarray) else v))
                elif inner[1][0] != "string":
                    parts.append((name, lambda v: v.tolist() if isinstance(v, np.ndarray) else v))
        if not parts:
            return None
        cls = dds_class(type_name)
        names = [name for name, _ in _fielddefs(type_name)]

        def plain(obj: Any) -> Any:
            changed = {name: fn(getattr(obj, name)) for name, fn in parts}
            if all(changed[name] is getattr(obj, name) for name in changed):
                return obj
            return cls(**{name: changed[name] if name in changed else getattr(obj, name) for name in names})

        _plain[type_name] = plain
        return plain


def plain_sequences(obj: Any, type_name: str) -> Any:
    """Return ``obj``, or a copy with numpy arrays in numeric sequence fields turned into lists/bytes.

    cyclonedds-python 11.0.1 tests ``if value:`` on sequences: a numpy array raises, and a one-element
    array holding 0 is silently written as a count without data (malformed CDR). Publishers call this.

    Parameters
    ----------
    obj : IdlStruct
        A DDS object of :func:`dds_class` ``(type_name)``.
    type_name : str
        Its ROS type name.

    Returns
    -------
    IdlStruct
        ``obj`` itself when nothing needed converting.
    """
    fn = _compile_plain(type_name)
    return obj if fn is None else fn(obj)
