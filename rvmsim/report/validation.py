"""The validation page: one self-contained HTML page for a scene validated against a capture.

Verdict table, pose correction with σ, the terminal summary and the pictures (PNG data
URIs), built with the page kit (:mod:`.page`).  Every string from a user's files (scene
name, capture path) is HTML-escaped.
"""

from __future__ import annotations

import json
from pathlib import Path

from .._io import write_png
from ..errors import RvmsimError
from ..tune import json_default
from ..validate import Validation
from .page import escape, img_tag, page

__all__ = ["validation_page", "write_validation_outputs", "PICTURE_CAPTIONS"]

#: Caption of each validation picture, by file stem.
PICTURE_CAPTIONS: dict[str, str] = {
    "landmarks": "Landmarks: predicted from the scene (red +, error line drawn 5× long), "
                 "found (green o), outliers (orange x), after correction (cyan dot)",
    "overlay": "Capture and synthetic frame blended (scene's pose)",
    "overlay_corrected": "Capture and synthetic frame blended (corrected pose)",
    "edges": "Edges: capture green, synthetic magenta, both white (scene's pose)",
    "edges_corrected": "Edges after the pose correction",
    "rvm_capture": "Capture through the ISP",
    "rvm_synthetic": "Synthetic frame through the ISP",
    "rvm_overlay": "RVM images blended",
    "rvm_edges": "RVM edges: capture green, synthetic magenta",
}

#: Longest side of an embedded picture, px.
PICTURE_MAX_PX = 960


def validation_page(result: Validation) -> str:
    """The whole HTML document for ``result``: verdict, numbers, pictures."""
    verdict = "PASS" if result.passed else "FAIL"
    return page(f"Validation: {result.scene_name}", f"""
<h1>Validation of {escape(result.scene_name)}: {verdict}</h1>
<p>Capture: {escape(result.capture)}, {result.image_size[0]}×{result.image_size[1]} px.
{result.n_inliers} landmarks matched ({result.n_found} found,
{result.n_predicted} predicted visible).</p>
<h2>Verdict</h2><table><tr><th>check</th><th>value</th><th>limit</th><th></th>
<th>what to fix</th></tr>{_check_rows(result)}</table>
<h2>Pose correction</h2><table><tr><th></th><th>change</th><th>σ</th><th></th></tr>{_pose_rows(result)}
</table>
<pre>{escape(result.summary())}</pre>
<h2>Pictures</h2>{_figures(result)}
""")


def _check_rows(result: Validation) -> str:
    return "".join(
        f'<tr class="{"pass" if k.passed else "fail"}"><td>{escape(k.name)}</td>'
        f"<td>{k.value:.3g}</td><td>≤ {k.limit:g}</td><td>{'pass' if k.passed else 'FAIL'}"
        f"</td><td>{'' if k.passed else escape(k.hint)}</td></tr>"
        for k in result.checks
    )


def _pose_rows(result: Validation) -> str:
    c = result.correction
    return "".join(
        f"<tr><td>{escape(n)}</td><td>{v:+.2f}</td><td>± {s:.2f}</td><td>{escape(u)}</td></tr>"
        for n, v, s, u in (
            ("Δx (driver side)", c.d_position_mm[0], c.sigma_position_mm[0], "mm"),
            ("Δy (down)", c.d_position_mm[1], c.sigma_position_mm[1], "mm"),
            ("Δz (rearward)", c.d_position_mm[2], c.sigma_position_mm[2], "mm"),
            ("Δyaw", c.d_yaw_deg, c.sigma_angles_deg[0], "°"),
            ("Δpitch", c.d_pitch_deg, c.sigma_angles_deg[1], "°"),
            ("Δroll", c.d_roll_deg, c.sigma_angles_deg[2], "°"),
        )
    )


def _figures(result: Validation) -> str:
    return "".join(
        f"<figure>{img_tag(img, name, PICTURE_MAX_PX)}<figcaption>"
        f"{escape(PICTURE_CAPTIONS.get(name, name))}</figcaption></figure>"
        for name, img in result.images.items()
    )


def write_validation_outputs(result: Validation, out_dir: str | Path) -> list[Path]:
    """Write ``validation.json``, ``validation.html`` and the PNGs into ``out_dir``.

    Returns
    -------
    list of Path
        ``validation.json``, ``validation.html``, then one PNG per picture (file stem =
        key of ``result.images``).

    Raises
    ------
    RvmsimError
        One line naming the folder or file that cannot be created or written.
    """
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise RvmsimError(f"{out}: cannot create output folder ({err.strerror or err})") from None
    paths = [write_png(out / f"{name}.png", img) for name, img in result.images.items()]
    js = out / "validation.json"
    try:
        js.write_text(json.dumps(result.to_dict(), indent=2, default=json_default) + "\n")
        html_path = out / "validation.html"
        html_path.write_text(validation_page(result))
    except OSError as err:
        raise RvmsimError(f"{out}: cannot write results ({err.strerror or err})") from None
    return [js, html_path, *paths]
