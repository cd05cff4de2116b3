"""Plain-language names and units of stored parameters, for people rather than programs."""

from __future__ import annotations

from bsp_ros.clinic.store.records import ParamKey

PART_NAMES = {
    "upper_arm": "Upper arm",
    "forearm": "Forearm",
    "hand": "Hand",
    "shoulder": "Shoulder",
    "elbow": "Elbow",
    "wrist": "Wrist",
}
PROXIMAL_JOINT = {"upper_arm": "shoulder", "forearm": "elbow", "hand": "wrist"}
# quantity key -> (label, unit); "{joint}" is the segment's proximal joint.
QUANTITIES = {
    "static_moment_kgm": ("static moment (weight lever arm about the {joint})", "kg·m"),
    "mass_kg": ("mass", "kg"),
    "com_m": ("centre of mass (distance from the {joint})", "m"),
    "first_moment_kgm": ("mass × centre-of-mass distance", "kg·m"),
    "length_m": ("length", "m"),
    "coulomb_nm": ("friction (passive moment)", "N·m"),
    "viscous_nms": ("damping (passive moment per speed)", "N·m·s/rad"),
    "stiffness_nm_per_rad": ("stiffness (passive moment per angle)", "N·m/rad"),
    "offset_rad": ("rest angle of the passive moment", "rad"),
}
# Unit suffixes of quantity keys not listed above, longest first.
UNIT_SUFFIXES = (
    ("_nm_per_rad", "N·m/rad"),
    ("_nms", "N·m·s/rad"),
    ("_kgm2", "kg·m²"),
    ("_kgm", "kg·m"),
    ("_rad", "rad"),
    ("_kg", "kg"),
    ("_nm", "N·m"),
    ("_m", "m"),
    ("_s", "s"),
)
GROUP_TITLES = {
    "joints": "Passive joint moments",
    "segments": "Arm segments",
}
_PART_ORDER = ("shoulder", "elbow", "wrist", "upper_arm", "forearm", "hand")
_QUANTITY_ORDER = tuple(QUANTITIES)


def part_name(part: str) -> str:
    """``forearm`` -> ``Forearm``; unknown parts are spelled out from their key."""
    return PART_NAMES.get(part, part.replace("_", " ").capitalize())


def unit(quantity: str) -> str:
    """The unit of a quantity key (``coulomb_nm`` -> ``N·m``), or ``""`` if it has none."""
    if quantity in QUANTITIES:
        return QUANTITIES[quantity][1]
    for suffix, name in UNIT_SUFFIXES:
        if quantity.endswith(suffix):
            return name
    return ""


def label(key: ParamKey) -> str:
    """A plain-language label, e.g. ``Elbow friction (passive moment)`` or ``Forearm static moment (...)``."""
    from bsp_ros.clinic.store.curves import angle_of

    _, part, quantity = key
    angle = angle_of(quantity)
    if angle is not None:
        return f"{part_name(part)} passive moment at {angle}°"
    if quantity in QUANTITIES:
        text = QUANTITIES[quantity][0]
    else:
        words = quantity
        for suffix, _ in UNIT_SUFFIXES:
            if quantity.endswith(suffix):
                words = quantity[: -len(suffix)]
                break
        text = words.replace("_", " ")
    joint = PROXIMAL_JOINT.get(part, "proximal joint")
    return f"{part_name(part)} {text.format(joint=joint)}"


def label_with_unit(key: ParamKey) -> str:
    """``label(key)`` followed by the unit in brackets, if any."""
    name = unit(key[2])
    return f"{label(key)} [{name}]" if name else label(key)


def sort_key(key: ParamKey) -> tuple[int, int, str, int, str]:
    """Order for display: joints before segments, proximal first, known quantities in a fixed order."""
    group, part, quantity = key
    part_rank = _PART_ORDER.index(part) if part in _PART_ORDER else len(_PART_ORDER)
    q_rank = _QUANTITY_ORDER.index(quantity) if quantity in _QUANTITY_ORDER else len(_QUANTITY_ORDER)
    from bsp_ros.clinic.store.curves import angle_of

    angle = angle_of(quantity)
    if angle is not None:  # curve points after the model's parameters, by angle
        return (0 if group == "joints" else 1, part_rank, part, len(_QUANTITY_ORDER) + 1, f"{angle + 1000:05d}")
    return (0 if group == "joints" else 1, part_rank, part, q_rank, quantity)


_PLAIN = {
    "coulomb_nm": "resistance to passive {joint} movement (friction)",
    "stiffness_nm_per_rad": "{joint} stiffness",
    "viscous_nms": "{joint} damping (resistance growing with speed)",
    "offset_nm": "{joint} passive moment offset",
    "static_moment_kgm": "arm weight about the {joint} (static moment)",
    "mass_kg": "{segment} mass",
    "com_m": "{segment} centre of mass",
    "first_moment_kgm": "{segment} mass × centre-of-mass distance",
    "length_m": "{segment} length",
}


def plain_name(key: ParamKey) -> str:
    """What a therapist calls a parameter, lower case: ``resistance to passive elbow movement (friction)``."""
    from bsp_ros.clinic.store.curves import angle_of

    _, part, quantity = key
    joint = PROXIMAL_JOINT.get(part, part).replace("_", " ")
    segment = part_name(part).lower()
    angle = angle_of(quantity)
    if angle is not None:
        return f"passive {part.replace('_', ' ')} moment at {angle}°"
    if quantity in _PLAIN:
        return _PLAIN[quantity].format(
            joint=joint if part in PROXIMAL_JOINT else part.replace("_", " "), segment=segment
        )
    return label(key).lower()


def plain_number(value: float | None, significant: int = 2) -> str:
    """``value`` rounded to ``significant`` digits, never in exponent notation: 0.38, 1.5, 12, 0.00007."""
    import math

    if value is None or not math.isfinite(value):
        return "–"
    if value == 0 or abs(value) < 5e-7:
        return "0"
    decimals = max(0, significant - 1 - math.floor(math.log10(abs(value))))
    decimals = min(decimals, 6)
    text = f"{round(value, decimals):.{decimals}f}"
    return "−" + text[1:] if text.startswith("-") else text


def with_unit(value: float | None, unit_text: str, significant: int = 2) -> str:
    """``0.38 N·m``."""
    return f"{plain_number(value, significant)} {unit_text}".strip()


_SHORT = {
    "coulomb_nm": "friction",
    "stiffness_nm_per_rad": "stiffness",
    "viscous_nms": "damping",
    "offset_nm": "passive offset",
    "static_moment_kgm": "static moment",
    "mass_kg": "mass",
    "com_m": "centre of mass",
    "first_moment_kgm": "mass × COM",
    "length_m": "length",
}


def short_label(key: ParamKey) -> str:
    """A panel title: ``Elbow friction``, ``Forearm static moment``, ``Elbow at 30°``."""
    from bsp_ros.clinic.store.curves import angle_of

    _, part, quantity = key
    angle = angle_of(quantity)
    if angle is not None:
        return f"{part_name(part)} moment at {angle}°"
    return f"{part_name(part)} {_SHORT.get(quantity, label(key).split(' ', 1)[-1])}"
