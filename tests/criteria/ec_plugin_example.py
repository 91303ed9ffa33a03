"""An example customer EC plugin (the worked example of docs/criteria.md).

"The calibration board is centred horizontally": the horizontal distance between the centre
of the board's bounding box and the centre of the RVM image, in % of the image width.
"""

from __future__ import annotations

from rvmsim import labels as L
from rvmsim.criteria import (
    Canvas,
    EcDefinition,
    EcValue,
    LabelGroup,
    LabelSource,
    Measurement,
    MeasureOptions,
    Sigmoid,
    bounding_box,
    label_mask,
    offset,
)

#: The board's pixels (the same group as EC 4-1's: same name, same labels, read once).
BOARD = LabelGroup("board", (L.BOARD,))


def board_centre_offset(src: LabelSource, options: MeasureOptions) -> Measurement:
    """|x of the board's centre − x of the image centre| / W, %; None without a board.

    Convention: pixel centres at integer columns; the board's centre is the midpoint of its
    leftmost and rightmost pixels, the image centre is at (W − 1)/2.
    """
    win = src.window(BOARD)
    box = bounding_box(label_mask(src.pixels(win), L.BOARD))
    if box is None:
        return Measurement(None)
    x, y, w, h = offset(box, win)
    centre = x + (w - 1) / 2.0
    width = src.shape[1]
    return Measurement(100.0 * abs(centre - (width - 1) / 2.0) / width, centre)


def draw_board_centre(canvas: Canvas, item: EcValue, centre: float | None) -> None:
    """A vertical line through the board's centre, labelled with the offset."""
    import cv2

    if centre is None:
        return
    h = canvas.shape[0]
    x = int(round(centre))
    cv2.line(canvas.image, (x, 0), (x, h - 1), canvas.status(item), canvas.line_width)
    canvas.text(f"board dx {canvas.value_text(item)}", (x + 4, h // 3), canvas.status(item))


ECS = [
    EcDefinition(
        id="acme-board-centred",
        name="board_centre_offset",
        unit="%",
        groups=(BOARD,),
        measure=board_centre_offset,
        annotate=draw_board_centre,
        default_range=(None, 5.0),
        default_sigmoid=Sigmoid.from_range(None, 5.0, tolerance=5.0),
        description="horizontal offset of the calibration board's centre from the image "
                    "centre / image width",
    ),
]
