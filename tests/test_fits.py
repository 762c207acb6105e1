"""Tests for jointplay.model.fits against published ISO 286 limit deviations.

Every expected value below was read off a published table, not computed from the
module's own data.  Sources (values in micrometres):

[DME6]  DME "Mold Bases & Plates", Technical Reference, "Tables for Determining Metric
        Tolerances", Table 6: Tolerances for inside dimensions (holes), ISO 286
        (https://online.flippingbook.com/view/962121/282).
[DME7]  same, Table 7: Tolerances for outside dimensions (shafts)
        (https://online.flippingbook.com/view/962121/284).
[DME8]  same, Table 8: S7 and U7 holes at preferred sizes
        (https://online.flippingbook.com/view/962121/287).
[DME9]  same, Table 9: s6 and u6 shafts at preferred sizes
        (https://online.flippingbook.com/view/962121/288).
[SUMI]  Sumitomo Electric tooling catalogue, "Dimensional Tolerances for Regularly Used
        Fits [Taken from JIS B 0401 (1999)]" -- JIS B 0401 is the Japanese adoption of
        ISO 286 (https://docs.steelcam.org/sumitomo/tehnicheskaya-informaciya-page28).
[MISU]  "Tolerances of regularly used hole fits, excerpts from JIS B 0401-1999"
        (https://info.5y1.org/gd-t-calculator-excel_1_480983.html).
[PUNCH] Punch Industry catalogue, shaft tolerances "JIS B 0401 (1998)"
        (https://punch-web.net/catalog_data/P6/pageindices/index1169.html).
[PON]   pon-osi.com, P7 hole table (JIS B 0401) (https://pon-osi.com/hameai-large-p7).
[SKF]   SKF, "Shaft tolerances and resultant fits", table 1 (f5, f6, g6 columns)
        (https://scribd.com/document/663845152/Tolerances-and-resultant-fits-for-shaft-SKF).
[COR1]  ISO 286-2:1988/Cor.1:2006, Technical Corrigendum 1 (corrects E8 80-120 mm to
        +126, R10 18-30 mm to -28, f9 250-315 mm to -186)
        (https://1library.net/document/y82v060y-iso-tolerance-part.html).
[MD]    K.L. Narayana, P. Kannaiah, K. Venkata Reddy, "Machine Drawing", ch. 15, Tables
        15.2 and 15.3: fundamental deviations of ISO 286-1, worked example "P7, 18 to 30
        mm: Delta = 8, hence ES = -14" (https://issuhub.com/view/index/5590?pageIndex=244).
[ZCC]   ZCC-CT catalogue, "Basic deviations value of shaft" a ... h, ISO 286-1
        (http://docs.steelcam.org/zcc-ct/katalog-frezy-so-smennymi-plastinami-page256).
[MECH]  mechguru.com, "DIN ISO 286 standard tolerance zone size table" (IT5 ... IT11)
        (http://mechguru.com/machine-design/din-iso-286-standard-tolerance-zone-size-table-
        different-grades-nominal-size).
[PRESS] PyPI project "pressfit", README examples "25 H7/g6" and "25 H7/p6"
        (https://pypi.org/project/pressfit/).
"""

from __future__ import annotations

import math

import pytest

from jointplay.model.fits import (
    Fit,
    Limits,
    fit,
    hole_limits,
    shaft_limits,
    tolerance_grade,
)

# ---------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------


def _um(limits: Limits) -> tuple[float, float]:
    """(upper, lower) in micrometres, rounded to the half micrometre ISO 286 uses."""
    return round(limits.upper * 2000) / 2, round(limits.lower * 2000) / 2


# Range upper bounds used by the standard's tables ("over ... up to and including").
FINE = (3, 6, 10, 14, 18, 24, 30, 40, 50, 65, 80, 100, 120)
FINE += (140, 160, 180, 200, 225, 250, 280, 315, 355, 400, 450, 500)
COARSE = (3, 6, 10, 18, 30, 50, 80, 120, 180, 250, 315, 400, 500)

# Sample sizes: the middle and the upper boundary of every range, plus small sizes.
SIZES = sorted(
    {0.5, 1.0, 1.5, 2.0, 3.0}
    | set(float(u) for u in FINE)
    | {(lo + hi) / 2 for lo, hi in zip((0, *FINE[:-1]), FINE, strict=True)}
)

SHAFT_LETTERS = [
    "a",
    "b",
    "c",
    "cd",
    "d",
    "e",
    "ef",
    "f",
    "fg",
    "g",
    "h",
    "js",
    "j",
    "k",
    "m",
    "n",
    "p",
    "r",
    "s",
    "t",
    "u",
    "v",
    "x",
    "y",
    "z",
    "za",
    "zb",
    "zc",
]
GRADES = range(5, 12)

# ---------------------------------------------------------------------------------------
# IT values: ISO 286-1 Table 1 [MECH]
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("grade", "diameter", "it_um"),
    [
        (5, 2, 4),  # [MECH] 0-3
        (7, 20, 21),  # [MECH] 18-30
        (7, 30, 21),  # boundary: 30 mm belongs to 18-30
        (7, 30.0001, 25),  # just above: 30-50
        (8, 150, 63),  # [MECH] 120-180
        (9, 300, 130),  # [MECH] 250-315
        (10, 350, 230),  # [MECH] 315-400
        (11, 500, 400),  # [MECH] 400-500
        (6, 450, 40),  # [MECH] 400-500
    ],
)
def test_it_values(grade: int, diameter: float, it_um: int) -> None:
    assert tolerance_grade(grade, diameter) == it_um / 1000


def test_it_grade_errors() -> None:
    with pytest.raises(ValueError, match="grades 5 to 11"):
        tolerance_grade(4, 10)
    with pytest.raises(ValueError, match="grades 5 to 11"):
        tolerance_grade(12, 10)
    with pytest.raises(TypeError):
        tolerance_grade(7.0, 10)  # type: ignore[arg-type]


# ---------------------------------------------------------------------------------------
# Published limit deviations (upper, lower in um)
# ---------------------------------------------------------------------------------------

HOLE_POINTS: list[tuple[str, float, float, float, str]] = [
    ("H7", 20, 21, 0, "brief / [PRESS]"),
    ("H11", 25, 130, 0, "[DME6]"),
    # K: ES = -k + Delta (ISO 286-1 Table 3)
    ("K6", 25, 2, -11, "[DME6]"),
    ("K7", 25, 6, -15, "[DME6]"),
    ("K8", 25, 10, -23, "[DME6]"),
    ("K7", 40, 7, -18, "[DME6]"),
    ("K7", 60, 9, -21, "[DME6]"),
    ("K7", 100, 10, -25, "[DME6]"),
    ("K7", 150, 12, -28, "[DME6]"),
    ("K7", 200, 13, -33, "[DME6]"),
    ("K7", 250, 13, -33, "[DME6] 250 mm is in 180-250"),
    ("K6", 200, 5, -24, "[DME6]"),
    ("K8", 200, 22, -50, "[DME6]"),
    ("K7", 1, 0, -10, "[DME6] 0-1 row"),
    # M
    ("M6", 40, -4, -20, "[DME6]"),
    ("M7", 25, 0, -21, "[DME6]"),
    ("M7", 200, 0, -46, "[DME6]"),
    ("M6", 200, -8, -37, "[DME6]"),
    ("M8", 200, 9, -63, "[DME6]"),
    ("M8", 25, 4, -29, "[DME6]"),
    # N
    ("N6", 25, -11, -24, "[DME6]"),
    ("N7", 25, -7, -28, "[DME6]"),
    ("N8", 25, -3, -36, "[DME6]"),
    ("N7", 40, -8, -33, "[DME6]"),
    ("N7", 100, -10, -45, "[DME6]"),
    ("N6", 100, -16, -38, "[DME6]"),
    ("N7", 200, -14, -60, "[DME6]"),
    ("N8", 200, -5, -77, "[DME6]"),
    # P (Delta rule for grades <= 7)
    ("P7", 2, -6, -16, "[PON]"),
    ("P7", 12, -11, -29, "[PON]"),
    ("P7", 25, -14, -35, "[PON], [MD] worked example"),
    ("P7", 60, -21, -51, "[PON]"),
    ("P7", 250, -33, -79, "[PON]"),
    ("P7", 300, -36, -88, "[PON]"),
    ("P7", 400, -41, -98, "[PON]"),
    ("P7", 500, -45, -108, "[PON]"),
    # R7 over the whole table
    ("R7", 25, -20, -41, "[DME6]"),
    ("R7", 60, -30, -60, "[DME6]"),
    ("R7", 70, -32, -62, "[DME6]"),
    ("R7", 90, -38, -73, "[DME6]"),
    ("R7", 110, -41, -76, "[DME6]"),
    ("R7", 130, -48, -88, "[DME6]"),
    ("R7", 150, -50, -90, "[DME6]"),
    ("R7", 170, -53, -93, "[DME6]"),
    ("R7", 190, -60, -106, "[DME6]"),
    ("R7", 210, -63, -109, "[DME6]"),
    ("R7", 240, -67, -113, "[DME6]"),
    ("R7", 260, -74, -126, "[DME6]"),
    # S7 / U7 at preferred sizes up to 500 mm
    ("S7", 2, -14, -24, "[DME8]"),
    ("U7", 2, -18, -28, "[DME8]"),
    ("S7", 5, -15, -27, "[DME8]"),
    ("U7", 5, -19, -31, "[DME8]"),
    ("S7", 10, -17, -32, "[DME8]"),
    ("U7", 10, -22, -37, "[DME8]"),
    ("S7", 16, -21, -39, "[DME8]"),
    ("U7", 16, -26, -44, "[DME8]"),
    ("S7", 20, -27, -48, "[DME8]"),
    ("U7", 20, -33, -54, "[DME8]"),
    ("U7", 25, -40, -61, "[DME8]"),
    ("S7", 40, -34, -59, "[DME8]"),
    ("U7", 40, -51, -76, "[DME8]"),
    ("U7", 50, -61, -86, "[DME8]"),
    ("S7", 60, -42, -72, "[DME8]"),
    ("U7", 60, -76, -106, "[DME8]"),
    ("S7", 80, -48, -78, "[DME8]"),
    ("U7", 80, -91, -121, "[DME8]"),
    ("S7", 100, -58, -93, "[DME8]"),
    ("U7", 100, -111, -146, "[DME8]"),
    ("S7", 120, -66, -101, "[DME8]"),
    ("U7", 120, -131, -166, "[DME8]"),
    ("S7", 160, -85, -125, "[DME8]"),
    ("U7", 160, -175, -215, "[DME8]"),
    ("S7", 200, -105, -151, "[DME8]"),
    ("U7", 200, -219, -265, "[DME8]"),
    ("S7", 250, -123, -169, "[DME8]"),
    ("U7", 250, -267, -313, "[DME8]"),
    ("S7", 300, -150, -202, "[DME8]"),
    ("U7", 300, -330, -382, "[DME8]"),
    ("S7", 400, -187, -244, "[DME8]"),
    ("U7", 400, -414, -471, "[DME8]"),
    ("S7", 500, -229, -292, "[DME8]"),
    ("U7", 500, -517, -580, "[DME8]"),
    ("X7", 20, -46, -67, "[MISU]"),
    ("X7", 25, -56, -77, "[MISU]"),
    # J (tabulated)
    ("J6", 25, 8, -5, "[DME6]"),
    ("J7", 25, 12, -9, "[DME6]"),
    ("J8", 25, 20, -13, "[DME6]"),
    ("J6", 200, 22, -7, "[DME6]"),
    ("J7", 200, 30, -16, "[DME6]"),
    ("J8", 200, 47, -25, "[DME6]"),
    ("J7", 2, 4, -6, "[DME6]"),
    # JS: +-IT/2 as printed (no rounding)
    ("JS6", 25, 6.5, -6.5, "[DME6]"),
    ("JS7", 25, 10.5, -10.5, "[DME6]"),
    ("JS8", 25, 16.5, -16.5, "[DME6]"),
    ("JS9", 25, 26, -26, "[DME6]"),
    ("JS7", 100, 17.5, -17.5, "[DME6]"),
    ("JS6", 200, 14.5, -14.5, "[DME6]"),
    ("JS9", 200, 57.5, -57.5, "[DME6]"),
    # A ... H
    ("F7", 25, 41, 20, "[MISU]"),
    ("F8", 25, 53, 20, "[MISU]"),
    ("F8", 40, 64, 25, "[MISU]"),
    ("G6", 25, 20, 7, "[MISU]"),
    ("G7", 25, 28, 7, "[MISU]"),
    ("G7", 40, 34, 9, "[MISU]"),
    ("D9", 25, 117, 65, "[MISU]"),
    ("E8", 25, 73, 40, "[MISU]"),
    # corrected by ISO 286-2 Technical Corrigendum 1
    ("E8", 100, 126, 72, "[COR1]"),
    ("R10", 25, -28, -112, "[COR1]"),
]

SHAFT_POINTS: list[tuple[str, float, float, float, str]] = [
    ("g6", 20, -7, -20, "brief / [PRESS]"),
    ("h6", 25, 0, -13, "[SUMI]"),
    ("f7", 25, -20, -41, "[SUMI]"),
    ("f8", 25, -20, -53, "[SUMI]"),
    ("e7", 25, -40, -61, "[SUMI]"),
    ("e8", 25, -40, -73, "[SUMI]"),
    ("d9", 25, -65, -117, "[SUMI]"),
    ("b9", 2, -140, -165, "[SUMI]"),
    ("js5", 25, 4.5, -4.5, "[SUMI]"),
    ("js6", 25, 6.5, -6.5, "[SUMI]"),
    ("js7", 25, 10.5, -10.5, "[SUMI]"),
    ("k5", 25, 11, 2, "[SUMI]"),
    ("k6", 25, 15, 2, "[SUMI]"),
    ("k6", 5, 9, 1, "[SUMI]"),
    ("k6", 2, 6, 0, "[SUMI]"),
    ("k6", 60, 21, 2, "[DME8] worked example"),
    ("m5", 25, 17, 8, "[SUMI]"),
    ("m6", 25, 21, 8, "[SUMI]"),
    ("m6", 5, 12, 4, "[SUMI]"),
    ("n6", 25, 28, 15, "[SUMI]"),
    ("p6", 25, 35, 22, "[SUMI]"),
    ("p6", 2, 12, 6, "[SUMI]"),
    ("r6", 25, 41, 28, "[SUMI]"),
    ("r6", 2, 16, 10, "[SUMI]"),
    ("s6", 25, 48, 35, "[SUMI]"),
    ("s6", 2, 20, 14, "[SUMI]"),
    ("t6", 25, 54, 41, "[SUMI]"),
    ("t6", 45, 70, 54, "[SUMI]"),
    ("t6", 60, 85, 66, "[SUMI]"),
    ("u6", 20, 54, 41, "[SUMI]"),
    ("u6", 25, 61, 48, "[SUMI]"),
    ("u6", 45, 86, 70, "[SUMI]"),
    ("u6", 60, 106, 87, "[SUMI]"),
    ("u6", 2, 24, 18, "[SUMI]"),
    ("x6", 2, 26, 20, "[SUMI]"),
    ("x6", 12, 51, 40, "[SUMI]"),
    ("x6", 15, 56, 45, "[SUMI]"),
    ("x6", 20, 67, 54, "[SUMI]"),
    ("x6", 25, 77, 64, "[SUMI]"),
    ("s6", 250, 169, 140, "[DME9]"),
    ("u6", 250, 313, 284, "[DME9]"),
    ("s6", 300, 202, 170, "[DME9]"),
    ("u6", 300, 382, 350, "[DME9]"),
    ("s6", 400, 244, 208, "[DME9]"),
    ("u6", 400, 471, 435, "[DME9]"),
    ("s6", 500, 292, 252, "[DME9]"),
    ("u6", 500, 580, 540, "[DME9]"),
    # a, b, c, including large sizes
    ("a11", 2, -270, -330, "[DME7]"),
    ("a11", 5, -270, -345, "[DME7]"),
    ("a11", 8, -280, -370, "[DME7]"),
    ("a11", 15, -290, -400, "[DME7]"),
    ("a11", 25, -300, -430, "[DME7]"),
    ("a11", 500, -1650, -2050, "[ZCC] es = -1650 with IT11 = 400 [MECH]"),
    ("b8", 2, -140, -154, "[DME7]"),
    ("b8", 270, -480, -561, "[DME7]"),
    ("b8", 500, -840, -937, "[DME7]"),
    ("b11", 300, -540, -860, "[DME7]"),
    ("b11", 350, -600, -960, "[DME7]"),
    ("b9", 450, -760, -915, "[PUNCH]"),
    ("b9", 500, -840, -995, "[PUNCH]"),
    ("c9", 420, -440, -595, "[PUNCH]"),
    ("c9", 500, -480, -635, "[PUNCH]"),
    ("c11", 2, -60, -120, "[DME7]"),
    ("c11", 25, -110, -240, "[DME7]"),
    # large sizes, other letters
    ("d8", 500, -230, -327, "[PUNCH]"),
    ("d9", 500, -230, -385, "[PUNCH]"),
    ("e9", 500, -135, -290, "[PUNCH]"),
    ("f8", 500, -68, -165, "[PUNCH]"),
    ("g5", 500, -20, -47, "[PUNCH]"),
    ("g6", 500, -20, -60, "[PUNCH]"),
    ("h7", 500, 0, -63, "[PUNCH]"),
    ("f5", 300, -56, -79, "[SKF]"),
    ("f6", 300, -56, -88, "[SKF]"),
    ("g6", 200, -15, -44, "[SKF]"),
    ("f9", 300, -56, -186, "[COR1]"),
]


@pytest.mark.parametrize(("cls", "diameter", "upper", "lower", "source"), HOLE_POINTS)
def test_published_hole_deviations(
    cls: str, diameter: float, upper: float, lower: float, source: str
) -> None:
    assert _um(hole_limits(cls, diameter)) == (upper, lower), source


@pytest.mark.parametrize(("cls", "diameter", "upper", "lower", "source"), SHAFT_POINTS)
def test_published_shaft_deviations(
    cls: str, diameter: float, upper: float, lower: float, source: str
) -> None:
    assert _um(shaft_limits(cls, diameter)) == (upper, lower), source


def test_results_are_millimetres() -> None:
    lim = hole_limits("H7", 20)
    assert lim == Limits(upper=0.021, lower=0.0)
    assert shaft_limits("g6", 20) == Limits(upper=-0.007, lower=-0.02)


# ---------------------------------------------------------------------------------------
# Delta rule, derived from the ISO 286-1 tables, at large sizes
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("cls", "diameter", "upper", "lower"),
    [
        # [MD] Table 15.3: K = -4 + Delta (315-400), -5 + Delta (400-500), Delta7 = 21, 23
        ("K7", 400, 17, -40),
        ("K7", 500, 18, -45),
        # M7 = -m + Delta7 = 0 everywhere; N7 = -n + Delta7 [MD]
        ("M7", 400, 0, -57),
        ("M7", 500, 0, -63),
        ("N7", 400, -16, -73),
        ("N7", 500, -17, -80),
        # M6 special case of ISO 286-1 (footnote of Table 3, [MD]): ES = -9, not -11
        ("M6", 300, -9, -41),
        ("M6", 250, -8, -37),  # 250 mm is still 180-250: no special case
        # above IT8: M = -m, N = 0 [MD]
        ("M9", 300, -20, -150),
        ("N9", 300, 0, -130),
        ("N9", 2, -4, -29),
    ],
)
def test_delta_rule_large_sizes(cls: str, diameter: float, upper: float, lower: float) -> None:
    assert _um(hole_limits(cls, diameter)) == (upper, lower)


# IT4 from ISO 286-1 Table 1 (needed to check Delta for grade 5).
IT4 = (3, 4, 4, 5, 6, 7, 8, 10, 12, 14, 16, 18, 20)


def _coarse_index(d: float) -> int:
    return next(i for i, hi in enumerate(COARSE) if d <= hi)


@pytest.mark.parametrize("diameter", SIZES)
def test_delta_is_it_step(diameter: float) -> None:
    """ISO 286-1: Delta = IT(n) - IT(n-1) above 3 mm, 0 up to 3 mm.

    Checked through the public API: ES(P_n) - ES(P_8) = Delta_n for n = 5 ... 7 and
    ES(M_n) - ES(M_9) = Delta_n for n = 5 ... 8 (except the M6 special case).
    """
    d = diameter
    it = {g: round(tolerance_grade(g, d) * 1000) for g in GRADES}
    it[4] = IT4[_coarse_index(d)]
    for n in (5, 6, 7):
        delta = hole_limits(f"P{n}", d).upper - hole_limits("P8", d).upper
        expected = 0 if d <= 3 else it[n] - it[n - 1]
        assert round(delta * 1000) == expected, (n, d)
    for n in (5, 6, 7, 8):
        if n == 6 and 250 < d <= 315:
            continue
        delta = hole_limits(f"M{n}", d).upper - hole_limits("M9", d).upper
        expected = 0 if d <= 3 else it[n] - it[n - 1]
        assert round(delta * 1000) == expected, (n, d)


def _clearances(f: Fit) -> tuple[float, float]:
    return f.min_clearance, f.max_clearance


@pytest.mark.parametrize("diameter", [d for d in SIZES if d > 3])
def test_hole_basis_equals_shaft_basis(diameter: float) -> None:
    """The purpose of Delta: H(n)/x(n-1) gives the same fit as X(n)/h(n-1)."""
    for letter in ["k", "m", "n", "p", "r", "s", "t", "u", "v", "x", "y", "z", "za", "zb"]:
        top = 8 if letter in ("k", "m", "n") else 7
        for n in range(6, top + 1):
            if letter == "m" and n == 6 and 250 < diameter <= 315:
                continue  # the M6 special case
            try:
                hole_basis = fit(f"H{n}/{letter}{n - 1}", diameter)
            except ValueError:
                continue  # t, v, y below their start
            shaft_basis = fit(f"{letter.upper()}{n}/h{n - 1}", diameter)
            assert _clearances(hole_basis) == _clearances(shaft_basis), (letter, n)


# ---------------------------------------------------------------------------------------
# Fits
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("spec", "diameter", "min_um", "max_um"),
    [
        ("H7/g6", 20, 7, 41),  # brief: hole +21/0, shaft -7/-20
        ("H7/g6", 25, 7, 41),  # [PRESS] "clearance 7 to 41 um"
        ("H7/p6", 25, -35, -1),  # [PRESS] "clearance_um (-35, -1)"
        ("H7/h6", 25, 0, 34),  # H7 +21/0 [brief], h6 0/-13 [SUMI]
        ("H8/f7", 25, 20, 74),  # H8 +33/0 (IT8 [MECH]), f7 -20/-41 [SUMI]
        ("H7/k6", 60, -21, 28),  # H7 +30/0, k6 +21/+2 [DME8 example]
        ("H7/s6", 25, -48, -14),  # s6 +48/+35 [SUMI]
        ("H11/c11", 25, 110, 370),  # H11 +130/0 [DME6], c11 -110/-240 [DME7]
        ("H7/u6", 500, -580, -477),  # H7 +63/0, u6 +580/+540 [DME9]
    ],
)
def test_fit_clearances(spec: str, diameter: float, min_um: int, max_um: int) -> None:
    f = fit(spec, diameter)
    assert f.min_clearance == min_um / 1000
    assert f.max_clearance == max_um / 1000
    assert f.mean_clearance == (min_um + max_um) / 2000


def test_fit_fields_and_spellings() -> None:
    f = fit("H7/g6", 20)
    assert (f.hole, f.shaft, f.diameter) == ("H7", "g6", 20.0)
    assert f.hole_limits == Limits(0.021, 0.0)
    assert f.shaft_limits == Limits(-0.007, -0.02)
    for spelling in ("H7-g6", " H7 / g6 ", "H7 - g6", "H7/ g6"):
        assert fit(spelling, 20) == f


def test_fit_js_mean_clearance_half_micrometres() -> None:
    f = fit("JS7/h6", 25)  # +-10.5 against 0/-13
    assert f.min_clearance == -0.0105
    assert f.max_clearance == 0.0235
    assert f.mean_clearance == 0.0065


# ---------------------------------------------------------------------------------------
# Boundaries: a size on a boundary belongs to the lower range
# ---------------------------------------------------------------------------------------


def test_boundary_rule() -> None:
    assert _um(hole_limits("K7", 30)) == (6, -15)  # 18-30, not 30-50
    assert _um(hole_limits("K7", 30.0001)) == (7, -18)
    assert _um(shaft_limits("g6", 30)) == (-7, -20)
    assert _um(shaft_limits("g6", 30.0001)) == (-9, -25)
    assert _um(hole_limits("U7", 24)) == (-33, -54)  # 18-24
    assert _um(hole_limits("U7", 24.0001)) == (-40, -61)  # 24-30
    assert _um(hole_limits("H7", 3)) == (10, 0)
    assert _um(hole_limits("H7", 500)) == (63, 0)
    assert _um(shaft_limits("t6", 24.5)) == (54, 41)


# ---------------------------------------------------------------------------------------
# js rounding option (ISO 286-1: for js7 ... js11 an odd IT "may" be rounded down)
# ---------------------------------------------------------------------------------------


def test_js_rounding_option() -> None:
    assert _um(hole_limits("JS7", 25, round_js=True)) == (10, -10)  # as [MISU] prints it
    assert _um(shaft_limits("js7", 100, round_js=True)) == (17, -17)
    # grade 6 is outside the rule; even IT values are untouched
    assert _um(shaft_limits("js6", 25, round_js=True)) == (6.5, -6.5)
    assert _um(shaft_limits("js7", 60, round_js=True)) == (15, -15)
    f = fit("H7/js7", 25, round_js=True)
    assert f.shaft_limits == Limits(0.01, -0.01)


# ---------------------------------------------------------------------------------------
# Properties over every class and range
# ---------------------------------------------------------------------------------------


def _expected_defined(kind: str, letter: str, grade: int, d: float) -> bool:
    """Where ISO 286-1 defines a class (independent restatement of its notes)."""
    low = letter.lower()
    if low in ("a", "b") and d <= 1:
        return False
    if low in ("cd", "ef", "fg") and d > 10:
        return False
    if low == "t" and d <= 24:
        return False
    if low == "v" and d <= 14:
        return False
    if low == "y" and d <= 18:
        return False
    if kind == "shaft" and low == "j":
        return grade in (5, 6, 7) or (grade == 8 and d <= 3)
    if kind == "hole" and low == "j":
        return grade in (6, 7, 8)
    if kind == "hole" and low == "k" and grade > 8:
        return d <= 3
    if kind == "hole" and low == "n" and grade > 8:
        return d > 1
    return True


def test_every_class_width_is_it_and_zero_lines() -> None:
    checked = 0
    for d in SIZES:
        for grade in GRADES:
            it = tolerance_grade(grade, d)
            for letter in SHAFT_LETTERS:
                for kind, name, func in (
                    ("shaft", f"{letter}{grade}", shaft_limits),
                    ("hole", f"{letter.upper()}{grade}", hole_limits),
                ):
                    if not _expected_defined(kind, letter, grade, d):
                        with pytest.raises(ValueError, match="ISO 286 defines"):
                            func(name, d)
                        continue
                    lim = func(name, d)
                    assert lim.upper - lim.lower == pytest.approx(it, abs=1e-12), (name, d)
                    assert math.isfinite(lim.upper)
                    checked += 1
                    if letter == "js":
                        assert lim.upper == -lim.lower
            assert hole_limits(f"H{grade}", d).lower == 0
            assert shaft_limits(f"h{grade}", d).upper == 0
    assert checked > 5000


@pytest.mark.parametrize("diameter", SIZES)
def test_hole_rules_against_shafts(diameter: float) -> None:
    """A ... H mirror the shaft es; P ... ZC above IT7 mirror the shaft ei."""
    d = diameter
    for grade in GRADES:
        for letter in ("a", "b", "c", "cd", "d", "e", "ef", "f", "fg", "g", "h"):
            if not _expected_defined("hole", letter, grade, d):
                continue
            assert hole_limits(f"{letter.upper()}{grade}", d).lower == -(
                shaft_limits(f"{letter}{grade}", d).upper
            )
        if grade < 8:
            continue
        for letter in ("p", "r", "s", "t", "u", "v", "x", "y", "z", "za", "zb", "zc"):
            if not _expected_defined("hole", letter, grade, d):
                continue
            assert hole_limits(f"{letter.upper()}{grade}", d).upper == -(
                shaft_limits(f"{letter}{grade}", d).lower
            )


# ---------------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda: shaft_limits("t6", 20), ["'t'", "24 mm"]),
        (lambda: hole_limits("T7", 24), ["'T'", "24 mm"]),
        (lambda: shaft_limits("v6", 14), ["'v'", "14 mm"]),
        (lambda: shaft_limits("y6", 18), ["'y'", "18 mm"]),
        (lambda: shaft_limits("cd6", 12), ["'cd'", "10 mm"]),
        (lambda: hole_limits("EF7", 11), ["'EF'", "10 mm"]),
        (lambda: shaft_limits("fg5", 400), ["'fg'", "10 mm"]),
        (lambda: shaft_limits("a11", 1), ["'a'", "1 mm"]),
        (lambda: hole_limits("B9", 0.5), ["'B'", "1 mm"]),
        (lambda: shaft_limits("j9", 10), ["'j'", "js9"]),
        (lambda: shaft_limits("j8", 5), ["j8", "3 mm"]),
        (lambda: hole_limits("J5", 10), ["'J'", "JS5"]),
        (lambda: hole_limits("K9", 10), ["'K'", "IT8", "3 mm"]),
        (lambda: hole_limits("N10", 1), ["'N'", "1 mm"]),
        (lambda: fit("H7/t6", 20), ["H7/t6", "'t'", "24 mm"]),
    ],
)
def test_undefined_classes(call: object, words: list[str]) -> None:
    assert callable(call)
    with pytest.raises(ValueError, match="ISO 286 defines") as info:
        call()
    for word in words:
        assert word in str(info.value)


def test_defined_at_the_edges() -> None:
    assert _um(shaft_limits("a11", 1.0001)) == (-270, -330)
    assert _um(shaft_limits("cd7", 10)) == (-56, -71)
    assert _um(hole_limits("K9", 3)) == (0, -25)
    assert _um(shaft_limits("j8", 3)) == (8, -6)
    assert _um(shaft_limits("v6", 14.5)) == (50, 39)


@pytest.mark.parametrize(
    ("spec", "words"),
    [
        ("H7g6", ["HOLE/SHAFT", "'H7/g6'"]),
        ("H7 g6", ["HOLE/SHAFT"]),
        ("H7//g6", ["HOLE/SHAFT"]),
        ("", ["HOLE/SHAFT"]),
        ("H7/", ["HOLE/SHAFT"]),
        ("7H/g6", ["HOLE/SHAFT"]),
        ("h7/G6", ["did you mean 'G6/h7'"]),
        ("H7/G6", ["'G6' is a hole class", "'g6'"]),
        ("h7/g6", ["'h7' is a shaft class", "'H7'"]),
        ("W7/g6", ["no fundamental deviation 'W'"]),
        ("H7/q6", ["no fundamental deviation 'q'"]),
        ("H4/g6", ["grades 5 to 11"]),
        ("H7/g12", ["grades 5 to 11"]),
        ("H07/g6", ["grades 5 to 11"]),
        ("Js7/h6", ["capitals", "'JS7'"]),
    ],
)
def test_bad_fit_specs(spec: str, words: list[str]) -> None:
    with pytest.raises(ValueError) as info:
        fit(spec, 20)
    for word in words:
        assert word in str(info.value)
    assert repr(spec) in str(info.value) or spec.strip() in str(info.value)


@pytest.mark.parametrize("cls", ["H", "7", "H7.5", "H 7", "HH7", "x"])
def test_bad_class_strings(cls: str) -> None:
    with pytest.raises(ValueError):
        hole_limits(cls, 20)


@pytest.mark.parametrize("diameter", [0, -1, 0.0, 500.0001, 501, 1000, math.nan, math.inf])
def test_sizes_out_of_range(diameter: float) -> None:
    for call in (
        lambda: hole_limits("H7", diameter),
        lambda: shaft_limits("g6", diameter),
        lambda: tolerance_grade(7, diameter),
        lambda: fit("H7/g6", diameter),
    ):
        with pytest.raises(ValueError, match="over 0 up to and including 500 mm"):
            call()


def test_non_numbers_rejected() -> None:
    with pytest.raises(TypeError):
        hole_limits("H7", "20")  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        hole_limits("H7", True)
    with pytest.raises(TypeError):
        fit(7, 20)  # type: ignore[arg-type]


def test_limits_validation() -> None:
    with pytest.raises(ValueError, match="below"):
        Limits(upper=-0.01, lower=0.0)
    with pytest.raises(ValueError, match="finite"):
        Limits(upper=math.nan, lower=0.0)
