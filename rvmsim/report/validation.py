"""The validation page: one self-contained HTML page for a scene validated against a capture.

Verdict table, pose correction with σ, the terminal summary and the pictures (PNG data
URIs), built with the page kit (:mod:`.page`).  Every string from a user's files (scene
name, capture path) is HTML-escaped.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .page import escape, img_tag, page

if TYPE_CHECKING:
    from ..validate import Validation

__all__ = ["validation_page", "PICTURE_CAPTIONS"]

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
