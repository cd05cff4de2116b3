"""Each source of uncertainty of an estimate's budget in a therapist's words, and what would shrink it."""

from __future__ import annotations

from bsp_ros.core.identification.ledger import Term

TERM_WORDS: dict[Term, str] = {
    Term.SENSOR_NOISE: "the force sensor's noise over a session of this length",
    Term.MARKER_PLACEMENT: "where the skin markers sit over the joints",
    Term.MODEL_CHOICE: "which passive-moment model fits (the movements cannot tell)",
    Term.FRICTION_SHAPE: "how the joint friction behaves at the slowest speeds",
    Term.DRIFT: "the force sensor drifting during the session",
    Term.SENSOR_ZERO: "the force sensor's zero (no tare)",
    Term.CONTACT_SLIP: "the hand slipping in the handle",
    Term.STATIC_MOMENT_BOUND: "an arm weight the session could not measure, held at zero",
    Term.WINDOW_CHECK: "the short window of the live estimate",
}
"""What each budget term is, for a reader who does not know the estimator."""

TERM_REMEDIES: dict[Term, str] = {
    Term.SENSOR_NOISE: "a longer session, or more movement",
    Term.MARKER_PLACEMENT: "markers placed firmly on their bony landmarks",
    Term.MODEL_CHOICE: "wider movements, each joint moved on its own (a protocol from bsp plan)",
    Term.FRICTION_SHAPE: "more changes of movement direction in the protocol",
    Term.DRIFT: "letting the force sensor warm up, then taring it again",
    Term.SENSOR_ZERO: "a tare: the force sensor recorded with the handle free before the session (bsp tare)",
    Term.CONTACT_SLIP: "a strap that keeps the hand against the handle's stop",
    Term.STATIC_MOMENT_BOUND: "a longer session, with more movement of that part of the arm",
    Term.WINDOW_CHECK: "a longer live window",
}
"""What would shrink each term, in the clinic's words (:attr:`Term.remedy` is the engineer's)."""

# With a tare applied, what is left of the sensor's zero is the tare's own uncertainty: another tare does not
# remove it, a better one (more samples of the still, free handle) shrinks it.
TARED_ZERO_WORDS = "the force sensor's zero (the tare's own uncertainty)"
TARED_ZERO_REMEDY = "a longer tare recording, with the handle free and still"


def term_of(name: str) -> Term | None:
    """The :class:`Term` a budget key names, None for a key this version does not know."""
    try:
        return Term(name)
    except ValueError:
        return None


def term_words(name: str, *, tared: bool) -> str:
    """A budget term in plain words: ``sensor_zero`` -> ``the force sensor's zero (no tare)``.

    Parameters
    ----------
    name : the budget key (a :class:`Term` value; an unknown key is spelled out).
    tared : whether the session was recorded with a tare (what is left of the sensor's zero then differs).
    """
    term = term_of(name)
    if term is None:
        return name.replace("_", " ")
    if term is Term.SENSOR_ZERO and tared:
        return TARED_ZERO_WORDS
    return TERM_WORDS[term]


def term_remedy(name: str, *, tared: bool) -> str:
    """What would shrink a budget term, in the clinic's words; ``""`` for a key this version does not know."""
    term = term_of(name)
    if term is None:
        return ""
    if term is Term.SENSOR_ZERO and tared:
        return TARED_ZERO_REMEDY
    return TERM_REMEDIES[term]


def engineer_remedy(name: str) -> str:
    """The estimator's own phrase for what shrinks a term (:attr:`Term.remedy`); ``""`` for an unknown key."""
    term = term_of(name)
    return term.remedy if term is not None else ""
