"""The expert console: a local web app to adjust a candidate live and watch the ECs respond
(``rvmsim console RUN_OR_SCENE``, see ``docs/console.md``).

Modules: :mod:`.session` (what it works on, one setting's evaluation), :mod:`.candidates`
(the run's candidates), :mod:`.inputs` (checking the browser's values), :mod:`.outputs`
(params files and setting reports, inside the run folder), :mod:`.pictures` (the pictures,
named by their parameters), :mod:`.guidelines` (the parking guidelines of a setting and
their ground error), :mod:`.guard` (the gate in front of every request: access,
origin, JSON writes, size limits), :mod:`.app` (the FastAPI app),
:mod:`.server` (access rule, socket, uvicorn); the page's HTML, JS and CSS in ``static/``.
"""

from __future__ import annotations

from .candidates import (
    candidate_json,
)
from .session import (
    CONSOLE_DIR,
    ConsoleFrame,
    ConsoleSession,
    ParamControl,
    evaluate_setting,
    jpeg_bytes,
    open_session,
    ec_margin,
    human_name,
)
from .pictures import Pictures, params_key, parse_params_key
from .guidelines import ConsoleGuidelines
from .guard import Guard, MAX_BODY_BYTES, MAX_TARGET_BYTES
from .inputs import ConsoleInputError, parse_params, parse_label
from .outputs import save_params, write_setting_report, params_text
from .app import create_app, session_json, TOKEN_HEADER, LOOPBACK_HOSTS
from .server import Access, check_access, is_loopback, listen, make_server, serve, console_url

__all__ = [
    "candidate_json",
    "CONSOLE_DIR",
    "ConsoleFrame",
    "ConsoleSession",
    "ParamControl",
    "evaluate_setting",
    "jpeg_bytes",
    "open_session",
    "ec_margin",
    "human_name",
    "Pictures",
    "params_key",
    "parse_params_key",
    "ConsoleGuidelines",
    "Guard",
    "MAX_BODY_BYTES",
    "MAX_TARGET_BYTES",
    "ConsoleInputError",
    "parse_params",
    "parse_label",
    "save_params",
    "write_setting_report",
    "params_text",
    "create_app",
    "session_json",
    "TOKEN_HEADER",
    "LOOPBACK_HOSTS",
    "Access",
    "check_access",
    "is_loopback",
    "listen",
    "make_server",
    "serve",
    "console_url",
]
