"""HTML review pages: the page kit, the run report, the sweep page, the validation page, the
robustness page, the EOL station's page and the sign-off sheet."""

from __future__ import annotations

from .run import (
    write_report,
    EC_GROUP_NAMES,
    SECTION_IDS,
    ec_section,
)
from .index import write_batch_report, write_any_report
from .sweep import (
    FeasibilityGrid,
    feasibility_grid,
    feasibility_png,
    yield_png,
    sensitivity_png,
    sweep_html,
    write_sweep_outputs,
)
from .validation import validation_page, write_validation_outputs, PICTURE_CAPTIONS
from .robustness import RobustnessInputs, robustness_page, write_robustness_outputs
from .robustness_markets import markets_robustness_page, write_markets_robustness_outputs
from .eol import eol_page, write_eol_page
from .signoff import SignoffResult, signoff
from .plots import (
    convergence_png,
    histogram_png,
)

__all__ = [
    "write_report",
    "write_batch_report",
    "write_any_report",
    "EC_GROUP_NAMES",
    "SECTION_IDS",
    "ec_section",
    "FeasibilityGrid",
    "feasibility_grid",
    "feasibility_png",
    "yield_png",
    "sensitivity_png",
    "sweep_html",
    "write_sweep_outputs",
    "validation_page",
    "write_validation_outputs",
    "PICTURE_CAPTIONS",
    "robustness_page",
    "write_robustness_outputs",
    "RobustnessInputs",
    "markets_robustness_page",
    "write_markets_robustness_outputs",
    "eol_page",
    "write_eol_page",
    "signoff",
    "SignoffResult",
    "convergence_png",
    "histogram_png",
]
