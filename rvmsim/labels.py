"""Label IDs: one integer per scene part, shared by the renderer, the ISP and the criteria.

The label image is ``uint8``; every ID below is < 256.  ID 0 is *void*: pixels outside the
lens's image circle.  Pixels where no geometry is hit see the sky.

The palette is the only place IDs are defined; everything else refers to names here.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

__all__ = [
    "VOID",
    "SKY",
    "GROUND",
    "BUMPER",
    "GARNISH",
    "TRUNK",
    "BOARD",
    "GROUND_PATTERN",
    "OBJECT_LETTERS",
    "object_body",
    "object_stripe",
    "object_patch",
    "GUIDE_SIDE_NEG_X",
    "GUIDE_SIDE_POS_X",
    "guide_cross",
    "MAX_CROSS_LINES",
    "GUIDE_PAINT_BASE",
    "guide_paint",
    "EXTRA_PART_BASE",
    "MAX_EXTRA_PARTS",
    "SITE_OBJECT_BASE",
    "MAX_SITE_OBJECTS",
    "site_object_labels",
    "BODY_LABELS",
    "label_names",
    "lut",
    "colorize",
]

VOID = 0
SKY = 1
GROUND = 2
BUMPER = 3
GARNISH = 4
TRUNK = 5
BOARD = 6
GROUND_PATTERN = 7  # black/white patterns lying on the ground (calibration mats)

OBJECT_LETTERS = ("A", "B", "C", "D", "E", "F", "G")
_OBJECT_BODY_BASE = 10  # 10..16: cylinder bodies A..G (everything not striped)
_OBJECT_STRIPE_BASE = 20  # 20..26: stripes A..E horizontal, F, G vertical (above the patch)
_OBJECT_PATCH_BASE = 27  # 27, 28: lower 150 mm x 150 mm of the F and G stripes

GUIDE_SIDE_NEG_X = 30  # side guideline on the -X (passenger) side
GUIDE_SIDE_POS_X = 31  # side guideline on the +X (driver) side
_GUIDE_CROSS_BASE = 40  # 41.. cross line 1 (nearest the bumper), 2, ...
MAX_CROSS_LINES = 19
# Lines painted to check the parking guidelines (rvmsim.guidelines.check): 60, 61, ...
GUIDE_PAINT_BASE = 60
_MAX_PAINTED = 40

EXTRA_PART_BASE = 100  # user-supplied extra meshes: 100, 101, ...
MAX_EXTRA_PARTS = 100

# Test objects of a site definition other than FMVSS 111's (rvmsim.scene.sitedefs): object k
# has its body 200 + 3k, its marked top band 201 + 3k and its top face 202 + 3k.
SITE_OBJECT_BASE = 200
MAX_SITE_OBJECTS = 18


def object_body(letter: str) -> int:
    """Label of the unmarked surface of test object ``letter`` (A–G)."""
    return _OBJECT_BODY_BASE + OBJECT_LETTERS.index(letter)


def object_stripe(letter: str) -> int:
    """Label of the stripe of object ``letter``: the horizontal band on A–E, the vertical
    stripe above the lower 150 mm patch on F and G."""
    return _OBJECT_STRIPE_BASE + OBJECT_LETTERS.index(letter)


def object_patch(letter: str) -> int:
    """Label of the lower 150 mm × 150 mm portion of the vertical stripe on F or G."""
    if letter not in ("F", "G"):
        raise ValueError(f"only F and G carry the lower stripe patch, not {letter!r}")
    return _OBJECT_PATCH_BASE + ("F", "G").index(letter)


def guide_cross(number: int) -> int:
    """Label of horizontal (cross) guideline ``number``; 1 is the nearest to the bumper."""
    if not 1 <= number <= MAX_CROSS_LINES:
        raise ValueError(f"cross guideline number must be 1..{MAX_CROSS_LINES}, got {number}")
    return _GUIDE_CROSS_BASE + number


def guide_paint(index: int) -> int:
    """Label of painted check line ``index`` (0, 1, …) of the parking guidelines' check
    (:mod:`rvmsim.guidelines.check`)."""
    if not 0 <= index < _MAX_PAINTED:
        raise ValueError(f"painted line index must be 0..{_MAX_PAINTED - 1}, got {index}")
    return GUIDE_PAINT_BASE + index


#: Labels of the car body: bumper, garnish, trunk and the user's extra parts.
BODY_LABELS: tuple[int, ...] = (BUMPER, GARNISH, TRUNK,
                                *range(EXTRA_PART_BASE, EXTRA_PART_BASE + MAX_EXTRA_PARTS))


def site_object_labels(index: int) -> tuple[int, int, int]:
    """Labels (body, marked top band, top face) of object ``index`` (0, 1, …) of a site
    definition (:mod:`rvmsim.scene.sitedefs`)."""
    if not 0 <= index < MAX_SITE_OBJECTS:
        raise ValueError(f"site object index must be 0..{MAX_SITE_OBJECTS - 1}, got {index}")
    base = SITE_OBJECT_BASE + 3 * index
    return (base, base + 1, base + 2)


def label_names() -> dict[int, str]:
    """Every fixed label ID with a readable name."""
    names = {
        VOID: "void",
        SKY: "sky",
        GROUND: "ground",
        BUMPER: "bumper",
        GARNISH: "garnish",
        TRUNK: "trunk",
        BOARD: "pattern_board",
        GROUND_PATTERN: "ground_pattern",
        GUIDE_SIDE_NEG_X: "guide_side_neg_x",
        GUIDE_SIDE_POS_X: "guide_side_pos_x",
    }
    for letter in OBJECT_LETTERS:
        names[object_body(letter)] = f"object_{letter}"
        names[object_stripe(letter)] = f"stripe_{letter}"
    for letter in ("F", "G"):
        names[object_patch(letter)] = f"stripe_{letter}_lower_patch"
    for n in range(1, MAX_CROSS_LINES + 1):
        names[guide_cross(n)] = f"guide_cross_{n}"
    for i in range(_MAX_PAINTED):
        names[guide_paint(i)] = f"guide_paint_{i}"
    for i in range(MAX_EXTRA_PARTS):
        names[EXTRA_PART_BASE + i] = f"extra_{i}"
    for k in range(MAX_SITE_OBJECTS):
        body, band, top = site_object_labels(k)
        names[body], names[band], names[top] = (f"site_object_{k}", f"site_object_{k}_band",
                                                f"site_object_{k}_top")
    return names


def lut(ids: Iterable[int]) -> np.ndarray:
    """A 256-entry uint8 table, 255 at ``ids`` and 0 elsewhere: ``cv2.LUT(labels, lut(ids))``
    is the mask of those labels in one pass."""
    table = np.zeros(256, np.uint8)
    table[list(ids)] = 255
    return table


def _palette() -> np.ndarray:
    """A 256×3 uint8 colour table for previews: fixed colours for the main parts, a
    deterministic spread of hues for the rest."""
    rng = np.random.default_rng(111)
    pal = rng.integers(40, 256, size=(256, 3)).astype(np.uint8)
    fixed = {
        VOID: (0, 0, 0),
        SKY: (135, 190, 235),
        GROUND: (90, 90, 90),
        BUMPER: (30, 60, 200),
        GARNISH: (40, 170, 60),
        TRUNK: (80, 200, 220),
        BOARD: (250, 250, 250),
        GROUND_PATTERN: (200, 200, 160),
        GUIDE_SIDE_NEG_X: (240, 200, 0),
        GUIDE_SIDE_POS_X: (240, 200, 0),
    }
    for i, letter in enumerate(OBJECT_LETTERS):
        fixed[object_body(letter)] = (200, 120 + 15 * i, 60)
        fixed[object_stripe(letter)] = (200, 20, 20 + 30 * i)
    fixed[object_patch("F")] = (255, 0, 255)
    fixed[object_patch("G")] = (255, 0, 255)
    for n in range(1, MAX_CROSS_LINES + 1):
        fixed[guide_cross(n)] = (255, max(0, 230 - 40 * n), 0)
    for k in range(MAX_SITE_OBJECTS):
        body, band, top = site_object_labels(k)
        fixed[body] = (220, 140 + 5 * k, 40)
        fixed[band] = (180, 20, 60 + 10 * k)
        fixed[top] = (255, 230, 120)
    for k, v in fixed.items():
        pal[k] = v
    return pal


PALETTE = _palette()
PALETTE.setflags(write=False)


def colorize(labels: np.ndarray) -> np.ndarray:
    """Preview colours for a label image.

    Parameters
    ----------
    labels : (H, W) uint8
        Label IDs.

    Returns
    -------
    rgb : (H, W, 3) uint8
    """
    labels = np.asarray(labels)
    if labels.dtype != np.uint8:
        raise TypeError(f"labels must be uint8, got {labels.dtype}")
    return PALETTE[labels]
