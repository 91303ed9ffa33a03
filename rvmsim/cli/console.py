"""``rvmsim console``: the expert console, a local web app (:mod:`rvmsim.console`)."""

from __future__ import annotations

from pathlib import Path

import click

from .errors import Command
from .params import Integer

__all__ = ["console"]


@click.command(cls=Command)
@click.argument("source", metavar="RUN_OR_SCENE", type=click.Path(path_type=Path))
@click.option("--port", type=Integer(0, 65535), default=8765, show_default=True,
              help="TCP port (0: any free port).")
@click.option("--host", default="127.0.0.1", show_default=True,
              help="Address to listen on; anything but loopback needs a token.")
@click.option("--token", default=None,
              help="Token every request must carry (16-128 of A-Z a-z 0-9 - _); made and "
                   "printed when --host is not loopback and none is given.")
@click.option("--no-browser", is_flag=True, help="Do not open a browser.")
def console(source: Path, port: int, host: str, token: str | None, no_browser: bool) -> None:
    """Adjust ISP parameters live in the browser and watch the ECs respond.

    RUN_OR_SCENE is a run folder (starts at rank 1, lists its candidates, saves into
    RUN/console/) or a scene file (starts at the paper's defaults, saves into
    out/<scene>/console/).  Stop with Ctrl-C.
    """
    from ..console import check_access, open_session, serve

    access = check_access(host, token)
    session = open_session(source)

    def ready(url: str) -> None:
        click.echo(f"rvmsim console of {session.scene.name}: {url}")
        if access.generated:
            click.echo(f"token (every request needs it): {access.token}")
        click.echo(f"saves go to {session.save_dir}; Ctrl-C stops")

    serve(session, access, port, on_ready=ready, open_browser=not no_browser)
