"""The EOL station as a scene: the car and its camera in front of the station's target.

:func:`station_scene` makes it from a scene with an ``eol`` section (:mod:`.eol`): the
vehicle, the ground and the target at the station's placement, nothing else (no FMVSS test
objects or guidelines, no other board or ground pattern).  :func:`eol_problem` is the check
made when a scene is read (the target exists, its placement is valid).
"""

from __future__ import annotations

from pydantic import ValidationError

from ..errors import SceneError
from .board import PatternBoard
from .eol import BOARD_TARGET
from .schema import GroundPattern, Scene

__all__ = ["station_scene", "station_target", "eol_problem"]


def _pattern(scene: Scene, name: str) -> GroundPattern | str:
    """The ground pattern called ``name`` (the station's own, then the test site's), or why
    there is none."""
    assert scene.eol is not None
    patterns = [*scene.eol.ground_patterns, *scene.test_site.ground_patterns]
    found = [p for p in patterns if p.name == name]
    if len(found) == 1:
        return found[0]
    if found:
        return (f"{name!r} names {len(found)} ground patterns (eol.ground_patterns, "
                "test_site.ground_patterns); give them distinct names")
    have = ", ".join(repr(p.name) for p in patterns) if patterns else "the scene has none"
    return (f"{name!r} is neither {BOARD_TARGET!r} nor the name of a ground pattern "
            f"({have})")


def _placed_board(scene: Scene) -> PatternBoard | str:
    """The station's board (``eol.board``, else test_site.board) at ``eol.pose``, or why
    it is invalid there."""
    assert scene.eol is not None
    board = scene.eol.board or scene.test_site.board
    pose = scene.eol.pose
    if pose is None:
        return board.model_copy(update={"enabled": True})
    data = {**board.model_dump(), **pose.overrides(), "enabled": True}
    try:
        return PatternBoard.model_validate(data)
    except ValidationError as err:
        e = err.errors(include_url=False)[0]
        msg = str(e["msg"]).removeprefix("Value error, ")
        return f"the board at this pose is invalid: {msg}"


def eol_problem(scene: Scene) -> tuple[str, str] | None:
    """(dotted key, one-line message) of an ``eol`` section that cannot be used, or None:
    a target that is neither the board nor exactly one ground pattern's name (the
    station's and the test site's), or a board whose placement at ``eol.pose`` is invalid
    (pitch or roll without ``placement: free``)."""
    spec = scene.eol
    if spec is None:
        return None
    if spec.is_board:
        board = _placed_board(scene)
        return ("eol.pose", board) if isinstance(board, str) else None
    found = _pattern(scene, spec.target)
    return ("eol.target", found) if isinstance(found, str) else None


def station_target(scene: Scene) -> PatternBoard | GroundPattern:
    """The station's target as placed there (a board, or a ground pattern).

    Raises
    ------
    SceneError
        The scene has no ``eol`` section, or it is unusable (:func:`eol_problem`).
    """
    spec = scene.eol
    if spec is None:
        raise SceneError(scene.source, "eol", "the scene has no eol section: add one naming "
                         "the station's target (docs/eol.md)")
    bad = eol_problem(scene)
    if bad is not None:
        raise SceneError(scene.source, *bad)
    if spec.is_board:
        board = _placed_board(scene)
        assert not isinstance(board, str)
        return board
    pattern = _pattern(scene, spec.target)
    assert not isinstance(pattern, str)
    return pattern.model_copy(update=spec.pose.overrides()) if spec.pose is not None else pattern


def station_scene(scene: Scene) -> Scene:
    """The EOL station: ``scene``'s camera (its mount as designed), vehicle, ground and
    render settings, with the station's target (:func:`station_target`) as the only
    fixture of its site.

    Raises
    ------
    SceneError
        The scene has no ``eol`` section, or it is unusable.
    """
    target = station_target(scene)
    site = scene.test_site
    if isinstance(target, PatternBoard):
        board, patterns = target, []
    else:
        board, patterns = site.board.model_copy(update={"enabled": False}), [target]
    station_site = site.model_copy(update={"fmvss": False, "board": board,
                                           "ground_patterns": patterns})
    return scene.model_copy(update={"test_site": station_site})
