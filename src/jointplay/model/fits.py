"""ISO 286 limits and fits: limit deviations of holes and shafts, exact to the micrometre.

Scope: standard tolerance grades IT5 to IT11, nominal sizes over 0 up to and including
500 mm, every fundamental deviation the standard defines there (shafts a ... zc, holes
A ... ZC, plus js/JS).

Where the numbers come from
---------------------------
Every table below is a literal transcription, in micrometres, of the tables of
ISO 286-1 (ISO system of limits and fits, Part 1: Bases of tolerances, deviations and
fits; 1988, same values in ISO 286-1:2010):

* ``_IT``          -- Table 1, standard tolerance grades IT5 ... IT11, 0 to 500 mm;
* ``_SHAFT_ES``    -- Table 2, shafts a ... h: upper deviation es, all grades;
* ``_SHAFT_J``, ``_SHAFT_K`` -- Table 2, shafts j and k: lower deviation ei;
* ``_SHAFT_EI``    -- Table 2, shafts m ... zc: lower deviation ei, all grades;
* ``_HOLE_J``      -- Table 3, holes J6, J7, J8: upper deviation ES;
* ``_DELTA``       -- Table 3, the Delta column (IT5 ... IT8 only; IT3/IT4 are not needed).

Holes are derived from those tables by the rules printed with ISO 286-1 Table 3, not by
a blanket "hole = -shaft" mirror:

* A ... H:  EI = -es of the same shaft letter;
* K, M, N up to IT8:  ES = -ei(k4..k7 / m / n) + Delta (K = 0, M = -2, N = -4 up to 3 mm);
* M above IT8: ES = -ei(m);  N above IT8: ES = 0 (-4 up to 3 mm);
  K above IT8: ES = 0 up to 3 mm, not defined above 3 mm;
* special case: M6 over 250 up to 315 mm has ES = -9 um (not -11);
* P ... ZC up to IT7: ES = -ei + Delta;  above IT7: ES = -ei;
* the other limit is always the fundamental one -/+ IT.

Notes of the standard that are applied: a, b, A, B are not defined at or below 1 mm;
N above IT8 is not defined at or below 1 mm; cd, ef, fg (and CD, EF, FG) are tabulated
only up to 10 mm; t/T start above 24 mm, v/V above 14 mm, y/Y above 18 mm; j exists for
grades 5, 6, 7 (and j8 up to 3 mm only); J for grades 6, 7, 8.

js / JS are +-IT/2 exactly, which is what the ISO 286-2 tables print (e.g. JS7 over 18 up
to 30 mm is +-10.5 um).  ISO 286-1 adds that for js7 ... js11 an odd IT value *may* be
rounded to the even value immediately below; that optional rounding is available with
``round_js=True`` and is off by default.

Results were checked against published ISO 286-2 / JIS B 0401 limit-deviation tables;
see ``tests/test_fits.py`` for the data points and their sources.

All table values are integer micrometres (js may give half micrometres); conversion to
millimetres happens only at the API edge.
"""

from __future__ import annotations

import math
import re
from bisect import bisect_left
from dataclasses import dataclass
from typing import Final, Literal

__all__ = [
    "Fit",
    "Limits",
    "fit",
    "hole_limits",
    "shaft_limits",
    "tolerance_grade",
]

# --------------------------------------------------------------------------------------
# Tables (micrometres).  Size ranges are "over <previous> up to and including <value>".
# --------------------------------------------------------------------------------------

#: The 25 ranges of the fundamental-deviation tables (intermediate steps included).
_FINE: Final[tuple[int, ...]] = (
    3, 6, 10, 14, 18, 24, 30, 40, 50, 65, 80, 100, 120,
    140, 160, 180, 200, 225, 250, 280, 315, 355, 400, 450, 500,
)  # fmt: skip
#: The 13 main ranges of the IT table (and of rows the standard prints merged).
_COARSE: Final[tuple[int, ...]] = (3, 6, 10, 18, 30, 50, 80, 120, 180, 250, 315, 400, 500)

_MIN_GRADE: Final = 5
_MAX_GRADE: Final = 11
_MAX_SIZE: Final = 500

# ISO 286-1 Table 1: standard tolerance grades, per main range.
_IT: Final[dict[int, tuple[int, ...]]] = {
    5: (4, 5, 6, 8, 9, 11, 13, 15, 18, 20, 23, 25, 27),
    6: (6, 8, 9, 11, 13, 16, 19, 22, 25, 29, 32, 36, 40),
    7: (10, 12, 15, 18, 21, 25, 30, 35, 40, 46, 52, 57, 63),
    8: (14, 18, 22, 27, 33, 39, 46, 54, 63, 72, 81, 89, 97),
    9: (25, 30, 36, 43, 52, 62, 74, 87, 100, 115, 130, 140, 155),
    10: (40, 48, 58, 70, 84, 100, 120, 140, 160, 185, 210, 230, 250),
    11: (60, 75, 90, 110, 130, 160, 190, 220, 250, 290, 320, 360, 400),
}

# ISO 286-1 Table 2, shafts a ... h, upper deviation es (all grades).  Rows of 13 values
# follow the main ranges (the standard prints them merged), rows of 25 the full ranges,
# rows of 3 stop at 10 mm (cd, ef, fg are tabulated only that far).
_SHAFT_ES_PRINTED: Final[dict[str, tuple[int, ...]]] = {
    "a": (
        -270, -270, -280, -290, -290, -300, -300, -310, -320, -340, -360, -380, -410,
        -460, -520, -580, -660, -740, -820, -920, -1050, -1200, -1350, -1500, -1650,
    ),
    "b": (
        -140, -140, -150, -150, -150, -160, -160, -170, -180, -190, -200, -220, -240,
        -260, -280, -310, -340, -380, -420, -480, -540, -600, -680, -760, -840,
    ),
    "c": (
        -60, -70, -80, -95, -95, -110, -110, -120, -130, -140, -150, -170, -180,
        -200, -210, -230, -240, -260, -280, -300, -330, -360, -400, -440, -480,
    ),
    "cd": (-34, -46, -56),
    "d": (-20, -30, -40, -50, -65, -80, -100, -120, -145, -170, -190, -210, -230),
    "e": (-14, -20, -25, -32, -40, -50, -60, -72, -85, -100, -110, -125, -135),
    "ef": (-10, -14, -18),
    "f": (-6, -10, -13, -16, -20, -25, -30, -36, -43, -50, -56, -62, -68),
    "fg": (-4, -6, -8),
    "g": (-2, -4, -5, -6, -7, -9, -10, -12, -14, -15, -17, -18, -20),
    "h": (0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0),
}  # fmt: skip

# ISO 286-1 Table 2, shafts m ... zc, lower deviation ei (all grades).  None = "—" in
# the standard (t starts above 24 mm, v above 14 mm, y above 18 mm).
_SHAFT_EI_PRINTED: Final[dict[str, tuple[int | None, ...]]] = {
    "m": (2, 4, 6, 7, 8, 9, 11, 13, 15, 17, 20, 21, 23),
    "n": (4, 8, 10, 12, 15, 17, 20, 23, 27, 31, 34, 37, 40),
    "p": (6, 12, 15, 18, 22, 26, 32, 37, 43, 50, 56, 62, 68),
    "r": (
        10, 15, 19, 23, 23, 28, 28, 34, 34, 41, 43, 51, 54,
        63, 65, 68, 77, 80, 84, 94, 98, 108, 114, 126, 132,
    ),
    "s": (
        14, 19, 23, 28, 28, 35, 35, 43, 43, 53, 59, 71, 79,
        92, 100, 108, 122, 130, 140, 158, 170, 190, 208, 232, 252,
    ),
    "t": (
        None, None, None, None, None, None, 41, 48, 54, 66, 75, 91, 104,
        122, 134, 146, 166, 180, 196, 218, 240, 268, 294, 330, 360,
    ),
    "u": (
        18, 23, 28, 33, 33, 41, 48, 60, 70, 87, 102, 124, 144,
        170, 190, 210, 236, 258, 284, 315, 350, 390, 435, 490, 540,
    ),
    "v": (
        None, None, None, None, 39, 47, 55, 68, 81, 102, 120, 146, 172,
        202, 228, 252, 284, 310, 340, 385, 425, 475, 530, 595, 660,
    ),
    "x": (
        20, 28, 34, 40, 45, 54, 64, 80, 97, 122, 146, 178, 210,
        248, 280, 310, 350, 385, 425, 475, 525, 590, 660, 740, 820,
    ),
    "y": (
        None, None, None, None, None, 63, 75, 94, 114, 144, 174, 214, 254,
        300, 340, 380, 425, 470, 520, 580, 650, 730, 820, 920, 1000,
    ),
    "z": (
        26, 35, 42, 50, 60, 73, 88, 112, 136, 172, 210, 258, 310,
        365, 415, 465, 520, 575, 640, 710, 790, 900, 1000, 1100, 1250,
    ),
    "za": (
        32, 42, 52, 64, 77, 98, 118, 148, 180, 226, 274, 335, 400,
        470, 535, 600, 670, 740, 820, 920, 1000, 1150, 1300, 1450, 1600,
    ),
    "zb": (
        40, 50, 67, 90, 108, 136, 160, 200, 242, 300, 360, 445, 525,
        620, 700, 780, 880, 960, 1050, 1200, 1300, 1500, 1650, 1850, 2100,
    ),
    "zc": (
        60, 80, 97, 130, 150, 188, 218, 274, 325, 405, 480, 585, 690,
        800, 900, 1000, 1150, 1250, 1350, 1550, 1700, 1900, 2100, 2400, 2600,
    ),
}  # fmt: skip

# ISO 286-1 Table 2, shaft j, lower deviation ei by grade (j8: up to 3 mm only).
_SHAFT_J: Final[dict[int, tuple[int, ...]]] = {
    5: (-2, -2, -2, -3, -4, -5, -7, -9, -11, -13, -16, -18, -20),
    6: (-2, -2, -2, -3, -4, -5, -7, -9, -11, -13, -16, -18, -20),
    7: (-4, -4, -5, -6, -8, -10, -12, -15, -18, -21, -26, -28, -32),
    8: (-6,),
}
# ISO 286-1 Table 2, shaft k, lower deviation ei for grades IT4 ... IT7 (0 otherwise).
_SHAFT_K4_7: Final[tuple[int, ...]] = (0, 1, 1, 1, 2, 2, 2, 3, 3, 4, 4, 4, 5)

# ISO 286-1 Table 3, hole J, upper deviation ES by grade.
_HOLE_J: Final[dict[int, tuple[int, ...]]] = {
    6: (2, 5, 5, 6, 8, 10, 13, 16, 18, 22, 25, 29, 33),
    7: (4, 6, 8, 10, 12, 14, 18, 22, 26, 30, 36, 39, 43),
    8: (6, 10, 12, 15, 20, 24, 28, 34, 41, 47, 55, 60, 66),
}
# ISO 286-1 Table 3, Delta for K, M, N (grades <= IT8) and P ... ZC (grades <= IT7).
_DELTA: Final[dict[int, tuple[int, ...]]] = {
    5: (0, 1, 2, 3, 3, 4, 5, 5, 6, 6, 7, 7, 7),
    6: (0, 3, 3, 3, 4, 5, 6, 7, 7, 9, 9, 11, 13),
    7: (0, 4, 6, 7, 8, 9, 11, 13, 15, 17, 20, 21, 23),
    8: (0, 6, 7, 9, 12, 14, 16, 19, 23, 26, 29, 32, 34),
}
# ISO 286-1 Table 3 footnote: M6 over 250 up to 315 mm has ES = -9 um instead of -11 um.
_M6_SPECIAL: Final = (250, 315, -9)

_COARSE_OF_FINE: Final[tuple[int, ...]] = tuple(bisect_left(_COARSE, u) for u in _FINE)


def _expand(row: tuple[int | None, ...]) -> tuple[int | None, ...]:
    """Spread a printed row over the 25 full ranges (None beyond a short row's end)."""
    if len(row) == len(_FINE):
        return row
    if len(row) == len(_COARSE):
        return tuple(row[c] for c in _COARSE_OF_FINE)
    return row + (None,) * (len(_FINE) - len(row))


_SHAFT_ES: Final[dict[str, tuple[int | None, ...]]] = {
    k: _expand(v) for k, v in _SHAFT_ES_PRINTED.items()
}
_SHAFT_EI: Final[dict[str, tuple[int | None, ...]]] = {
    k: _expand(v) for k, v in _SHAFT_EI_PRINTED.items()
}

_SHAFT_LETTERS: Final[frozenset[str]] = frozenset({*_SHAFT_ES, *_SHAFT_EI, "js", "j", "k"})
_ALL_LETTERS_TEXT: Final = "A B C CD D E EF F FG G H JS J K M N P R S T U V X Y Z ZA ZB ZC"

# --------------------------------------------------------------------------------------
# Public types
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Limits:
    """Upper and lower limit deviation from the nominal size, in millimetres."""

    upper: float
    lower: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.upper) and math.isfinite(self.lower)):
            raise ValueError(f"limit deviations must be finite numbers, got {self!r}")
        if self.upper < self.lower:
            raise ValueError(
                f"upper deviation {self.upper} mm is below lower deviation {self.lower} mm"
            )


@dataclass(frozen=True)
class Fit:
    """A hole class and a shaft class at one nominal size (deviations in mm)."""

    hole: str
    shaft: str
    diameter: float
    hole_limits: Limits
    shaft_limits: Limits

    @property
    def min_clearance(self) -> float:
        """Smallest clearance, mm (hole lower - shaft upper); negative means interference."""
        return round(self.hole_limits.lower - self.shaft_limits.upper, 9)

    @property
    def max_clearance(self) -> float:
        """Largest clearance, mm (hole upper - shaft lower); negative means interference."""
        return round(self.hole_limits.upper - self.shaft_limits.lower, 9)

    @property
    def mean_clearance(self) -> float:
        """Mean of the smallest and largest clearance, mm."""
        return round((self.min_clearance + self.max_clearance) / 2, 9)


# --------------------------------------------------------------------------------------
# Public functions
# --------------------------------------------------------------------------------------


def tolerance_grade(grade: int, diameter: float) -> float:
    """Standard tolerance ``IT<grade>`` at a nominal size, in mm (ISO 286-1 Table 1)."""
    if isinstance(grade, bool) or not isinstance(grade, int):
        raise TypeError(f"grade must be an int, got {grade!r}")
    _check_grade(grade, f"IT{grade}")
    _, coarse = _ranges(diameter)
    return _IT[grade][coarse] / 1000


def shaft_limits(cls: str, diameter: float, *, round_js: bool = False) -> Limits:
    """Limit deviations (mm) of a shaft class such as ``"g6"``, ``"k6"`` or ``"js7"``.

    ``round_js=True`` applies the optional ISO 286-1 rounding for js7 ... js11 (an odd IT
    value in micrometres is replaced by the even value below it before halving).
    """
    letter, grade = _parse_class(cls, "shaft")
    upper, lower = _shaft_um(letter, grade, diameter, cls.strip(), round_js)
    return Limits(upper / 1000, lower / 1000)


def hole_limits(cls: str, diameter: float, *, round_js: bool = False) -> Limits:
    """Limit deviations (mm) of a hole class such as ``"H7"``, ``"K7"`` or ``"JS8"``.

    ``round_js=True`` applies the optional ISO 286-1 rounding for JS7 ... JS11.
    """
    letter, grade = _parse_class(cls, "hole")
    upper, lower = _hole_um(letter, grade, diameter, cls.strip(), round_js)
    return Limits(upper / 1000, lower / 1000)


_FIT_RE: Final = re.compile(r"\s*([A-Za-z]+\d+)\s*[/-]\s*([A-Za-z]+\d+)\s*")
_FIT_HELP: Final = "write a fit as HOLE/SHAFT, like 'H7/g6' (or 'H7-g6')"


def fit(spec: str, diameter: float, *, round_js: bool = False) -> Fit:
    """Hole and shaft limits of a fit such as ``"H7/g6"`` (also ``"H7-g6"``, ``"H7 / g6"``)."""
    if not isinstance(spec, str):
        raise TypeError(f"a fit is written as a string like 'H7/g6', got {spec!r}")
    m = _FIT_RE.fullmatch(spec)
    if m is None:
        raise ValueError(f"{spec!r} is not a fit: {_FIT_HELP}")
    hole, shaft = m.group(1), m.group(2)
    if hole.islower() and shaft.isupper():
        raise ValueError(
            f"{spec!r}: the hole comes first, in capitals, and the shaft second, in lower "
            f"case; did you mean '{shaft}/{hole}'?"
        )
    try:
        hole_lim = hole_limits(hole, diameter, round_js=round_js)
        shaft_lim = shaft_limits(shaft, diameter, round_js=round_js)
    except ValueError as exc:
        raise ValueError(f"fit {spec!r}: {exc}") from None
    return Fit(hole, shaft, float(diameter), hole_lim, shaft_lim)


# --------------------------------------------------------------------------------------
# Internals
# --------------------------------------------------------------------------------------

_CLASS_RE: Final = re.compile(r"([A-Za-z]+)(\d+)")


def _parse_class(cls: str, kind: Literal["hole", "shaft"]) -> tuple[str, int]:
    """Split ``"H7"`` / ``"js6"`` into (lower-case letter code, grade), checking case."""
    if not isinstance(cls, str):
        raise TypeError(f"a tolerance class is a string like 'H7' or 'g6', got {cls!r}")
    example = "'H7'" if kind == "hole" else "'g6'"
    m = _CLASS_RE.fullmatch(cls.strip())
    if m is None:
        raise ValueError(
            f"{cls!r} is not an ISO 286 tolerance class: write the deviation letter(s) "
            f"and the grade, like {example}"
        )
    letters, digits = m.group(1), m.group(2)
    code = letters.lower()
    if code not in _SHAFT_LETTERS:
        raise ValueError(
            f"{cls!r}: ISO 286 has no fundamental deviation {letters!r}; holes use "
            f"{_ALL_LETTERS_TEXT} and shafts the same in lower case"
        )
    if kind == "hole" and letters != letters.upper():
        if letters == code:
            raise ValueError(
                f"{cls!r} is a shaft class (lower case); hole classes are written in "
                f"capitals, e.g. {letters.upper() + digits!r}"
            )
        raise ValueError(
            f"{cls!r}: write hole classes in capitals, e.g. {letters.upper() + digits!r}"
        )
    if kind == "shaft" and letters != code:
        if letters == letters.upper():
            raise ValueError(
                f"{cls!r} is a hole class (capitals); shaft classes are written in lower "
                f"case, e.g. {code + digits!r}"
            )
        raise ValueError(f"{cls!r}: write shaft classes in lower case, e.g. {code + digits!r}")
    grade = int(digits)
    if digits != str(grade):
        raise ValueError(
            f"{cls!r}: grade {digits!r} is not supported; ISO 286 grades 5 to 11 are "
            f"supported, like {example}"
        )
    _check_grade(grade, repr(cls))
    return code, grade


def _check_grade(grade: int, what: str) -> None:
    if not _MIN_GRADE <= grade <= _MAX_GRADE:
        raise ValueError(
            f"{what}: grade IT{grade} is not supported; ISO 286 grades 5 to 11 are supported"
        )


def _ranges(diameter: float) -> tuple[int, int]:
    """(full-range index, main-range index) of a nominal size; boundaries go down."""
    if isinstance(diameter, bool) or not isinstance(diameter, int | float):
        raise TypeError(f"the nominal size must be a number in mm, got {diameter!r}")
    if not (math.isfinite(diameter) and 0 < diameter <= _MAX_SIZE):
        raise ValueError(
            f"nominal size {diameter!r} mm is out of range: ISO 286 sizes handled here are "
            f"over 0 up to and including {_MAX_SIZE} mm"
        )
    fine = bisect_left(_FINE, diameter)
    return fine, _COARSE_OF_FINE[fine]


def _lower_bound(fine: int) -> int:
    return 0 if fine == 0 else _FINE[fine - 1]


def _lookup(row: tuple[int | None, ...], fine: int, what: str, diameter: float) -> int:
    """Value of a 25-range row, or a ValueError saying where ISO 286 defines it."""
    value = row[fine]
    if value is not None:
        return value
    defined = [i for i, v in enumerate(row) if v is not None]
    if fine < defined[0]:
        edge = _lower_bound(defined[0])
        where = f"at or below {edge} mm (it starts above {edge} mm)"
    else:
        edge = _FINE[defined[-1]]
        where = f"above {edge} mm (it is defined only up to {edge} mm)"
    raise ValueError(f"ISO 286 defines no {what} {where}; got {diameter:g} mm")


def _not_at_or_below_1mm(what: str, diameter: float) -> None:
    if diameter <= 1:
        raise ValueError(f"ISO 286 defines no {what} at or below 1 mm; got {diameter:g} mm")


def _js_um(it: int, grade: int, round_js: bool) -> tuple[float, float]:
    if round_js and grade >= 7 and it % 2 == 1:
        it -= 1
    return it / 2, -it / 2


def _shaft_um(
    letter: str, grade: int, diameter: float, name: str, round_js: bool
) -> tuple[float, float]:
    """(es, ei) in micrometres."""
    fine, coarse = _ranges(diameter)
    it = _IT[grade][coarse]
    if letter == "js":
        return _js_um(it, grade, round_js)
    if letter in _SHAFT_ES:
        if letter in ("a", "b"):
            _not_at_or_below_1mm(f"'{letter}' shaft deviation", diameter)
        es = _lookup(_SHAFT_ES[letter], fine, f"'{letter}' shaft deviation", diameter)
        return es, es - it
    if letter == "j":
        row = _SHAFT_J.get(grade)
        if row is None:
            raise ValueError(
                f"ISO 286 defines the 'j' shaft deviation only for grades 5, 6, 7 (and 8 up "
                f"to 3 mm); {name!r} is not defined (use 'js{grade}')"
            )
        if coarse >= len(row):
            raise ValueError(
                f"ISO 286 defines no 'j8' shaft deviation above 3 mm; got {diameter:g} mm"
            )
        ei = row[coarse]
        return ei + it, ei
    if letter == "k":
        ei = _SHAFT_K4_7[coarse] if grade <= 7 else 0
        return ei + it, ei
    ei = _lookup(_SHAFT_EI[letter], fine, f"'{letter}' shaft deviation", diameter)
    return ei + it, ei


def _hole_um(
    letter: str, grade: int, diameter: float, name: str, round_js: bool
) -> tuple[float, float]:
    """(ES, EI) in micrometres, by the hole rules of ISO 286-1 Table 3."""
    fine, coarse = _ranges(diameter)
    it = _IT[grade][coarse]
    cap = letter.upper()
    what = f"'{cap}' hole deviation"
    if letter == "js":
        return _js_um(it, grade, round_js)
    if letter in _SHAFT_ES:  # A ... H: EI = -es
        if letter in ("a", "b"):
            _not_at_or_below_1mm(what, diameter)
        ei = -_lookup(_SHAFT_ES[letter], fine, what, diameter)
        return ei + it, ei
    if letter == "j":
        row = _HOLE_J.get(grade)
        if row is None:
            raise ValueError(
                f"ISO 286 defines the 'J' hole deviation only for grades 6, 7, 8; {name!r} "
                f"is not defined (use 'JS{grade}')"
            )
        es = row[coarse]
    elif letter == "k":
        if grade <= 8:
            es = -_SHAFT_K4_7[coarse] + _DELTA[grade][coarse]
        elif coarse == 0:
            es = 0
        else:
            raise ValueError(
                f"ISO 286 defines 'K' holes above IT8 only up to 3 mm; {name!r} at "
                f"{diameter:g} mm is not defined"
            )
    elif letter == "m":
        m = _lookup(_SHAFT_EI["m"], fine, what, diameter)
        es = -m + _DELTA[grade][coarse] if grade <= 8 else -m
        lo, hi, special = _M6_SPECIAL
        if grade == 6 and lo < diameter <= hi:
            es = special
    elif letter == "n":
        if grade <= 8:
            es = -_lookup(_SHAFT_EI["n"], fine, what, diameter) + _DELTA[grade][coarse]
        else:
            _not_at_or_below_1mm(f"'N' hole deviation above IT8 ({name!r})", diameter)
            es = -4 if coarse == 0 else 0
    else:  # P ... ZC
        es = -_lookup(_SHAFT_EI[letter], fine, what, diameter)
        if grade <= 7:
            es += _DELTA[grade][coarse]
    return es, es - it
