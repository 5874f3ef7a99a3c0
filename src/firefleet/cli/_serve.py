"""``firefleet serve [RUN_DIR ...]``: the runs in a browser (see :mod:`firefleet.serve`)."""

from __future__ import annotations

import argparse
import threading
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from rich.console import Console

from firefleet.cli._console import EXIT_OK
from firefleet.errors import InputError

__all__ = [
    "LiveServer",
    "add_parsers",
    "add_run_flags",
    "check_port",
    "dashboard_screenshot",
    "live_mode",
    "mcap_of",
    "serve_forever",
    "url_of",
]


def add_parsers(sub: Any) -> None:
    """Add ``serve`` to the subcommands ``sub``."""
    serve = sub.add_parser("serve", help="show run folders in a browser (replay)")
    serve.add_argument(
        "folders",
        nargs="*",
        metavar="RUN_DIR",
        help="run folders, or folders holding them (default: runs)",
    )
    serve.add_argument("--host", default="127.0.0.1", help="address to bind")
    serve.add_argument("--port", type=int, default=8000, metavar="N", help="port")
    serve.add_argument(
        "--token",
        metavar="T",
        help="token every request must carry (required beyond loopback; "
        "default: a new one, printed, when --host is not loopback)",
    )
    serve.set_defaults(handler=cmd_serve)


def check_port(port: int, flag: str = "--port") -> int:
    """``port`` if it is 1..65535, else an :class:`InputError` naming ``flag``."""
    if not 0 < port < 65536:
        raise InputError(f"{flag} must be 1..65535, got {port}")
    return port


def url_of(host: str, port: int, token: str | None, path: str = "/") -> str:
    """The URL to open (with ``?token=`` when one is needed)."""
    shown = "127.0.0.1" if host in ("0.0.0.0", "::", "") else host
    shown = f"[{shown}]" if ":" in shown else shown
    return f"http://{shown}:{port}{path}" + (f"?token={token}" if token else "")


def access(host: str, token: str | None) -> tuple[str | None, bool]:
    """``(token, loopback_only)`` for a server bound to ``host``: beyond loopback a
    token is required (a new one if none was given)."""
    from firefleet.serve.security import is_loopback, new_token

    if token is not None and len(token) < 8:
        raise InputError(f"--token must be at least 8 characters, got {len(token)}")
    if is_loopback(host):
        return token, True
    return (token or new_token()), False


def serve_forever(app: Any, host: str, port: int) -> None:
    """Run ``app`` on uvicorn until interrupted."""
    import uvicorn

    uvicorn.run(
        app,
        host=host,
        port=port,
        log_level="warning",
        ws="websockets-sansio",
        timeout_graceful_shutdown=2,
    )


def cmd_serve(args: argparse.Namespace, out: Console, err: Console) -> int:
    """``firefleet serve``."""
    from firefleet.serve.app import create_app
    from firefleet.serve.runs import find_runs

    check_port(args.port)
    token, loopback_only = access(args.host, args.token)
    if not args.folders and not Path("runs").is_dir():
        raise InputError("RUN_DIR: none given and no runs/ folder here; name the run folders")
    runs = find_runs([Path(f) for f in args.folders or ["runs"]])
    app = create_app(runs, token=token, loopback_only=loopback_only)
    out.print(f"serving {len(runs)} run(s) at {url_of(args.host, args.port, token)}", markup=False)
    out.print("press Ctrl-C to stop", markup=False)
    serve_forever(app, args.host, args.port)
    return EXIT_OK


def dashboard_screenshot() -> bytes:
    """The PNG of a run page that the report's front page shows (``static/``)."""
    from importlib import resources

    return (resources.files("firefleet.serve") / "static" / "dashboard-run.png").read_bytes()


MCAP_AUTO_BYTES = 5_000_000
"""``run.mcap`` is written without ``--mcap`` when its estimate is under this [bytes]."""
MCAP_BYTES_PER_SAMPLE = 300
"""About what one robot's recorded sample takes in ``run.mcap`` [bytes] (measured:
coop-different-paths, 3 robots x 8,001 samples, 6.8 MB)."""


def mcap_wanted(choice: bool | None, samples: int, robots: int) -> bool:
    """Whether to write ``run.mcap``: as asked, or (``None``) when it is small.

    Examples
    --------
    >>> from firefleet.cli._serve import mcap_wanted
    >>> mcap_wanted(None, 201, 1), mcap_wanted(None, 8001, 3), mcap_wanted(True, 8001, 3)
    (True, False, True)
    """
    if choice is not None:
        return choice
    return samples * robots * MCAP_BYTES_PER_SAMPLE < MCAP_AUTO_BYTES


def add_run_flags(run: argparse.ArgumentParser) -> None:
    """``firefleet run``'s ``--mcap``, ``--live``, ``--serve-port``, ``--live-speed``."""
    run.add_argument(
        "--mcap",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="write run.mcap (Foxglove schemas, about 0.3 kB per robot and sample); by "
        f"default only when that is under {MCAP_AUTO_BYTES // 1_000_000} MB",
    )
    run.add_argument(
        "--live",
        action="store_true",
        help="show the run in a browser while it simulates (http://127.0.0.1:PORT/live)",
    )
    run.add_argument(
        "--serve-port", type=int, default=8000, metavar="N", help="the live page's port"
    )
    run.add_argument(
        "--live-speed",
        type=float,
        default=1.0,
        metavar="X",
        help="live: simulated seconds per second (0: as fast as it runs)",
    )


def mcap_of(result: Any, document: Mapping[str, Any]) -> bytes:
    """The ``run.mcap`` bytes of a run (:func:`firefleet.mcap_log.mcap_bytes`)."""
    from firefleet.mcap_log import mcap_bytes
    from firefleet.serve.scene import scene_of

    return mcap_bytes(result.arrays(), document=document, scene=scene_of(result.scenario))


class LiveServer:
    """The live page on uvicorn, in a thread of this process (loopback only)."""

    def __init__(self, app: Any, port: int) -> None:
        import uvicorn

        config = uvicorn.Config(
            app,
            host="127.0.0.1",
            port=port,
            log_level="warning",
            ws="websockets-sansio",
            timeout_graceful_shutdown=2,
        )
        self.server = uvicorn.Server(config)
        self.thread = threading.Thread(target=self.server.run, daemon=True)
        self.thread.start()
        deadline = time.monotonic() + 20.0
        while not self.server.started:
            if not self.thread.is_alive() or time.monotonic() > deadline:
                raise InputError(f"--serve-port {port}: cannot listen there (in use?)")
            time.sleep(0.02)

    def stop(self) -> None:
        """Stop serving (the open websockets are closed)."""
        self.server.should_exit = True
        self.thread.join(timeout=10.0)


@contextmanager
def live_mode(args: argparse.Namespace, out: Console) -> Iterator[Any]:
    """With ``--live``: serve the live page while the block runs, and yield the
    simulator that streams to it (``simulator(scenario, progress=...)``); else None."""
    if not getattr(args, "live", False):
        yield None
        return
    import numpy as np

    from firefleet.serve.app import create_app
    from firefleet.serve.live import LiveHub, simulate_live

    check_port(args.serve_port, "--serve-port")
    if not (args.live_speed >= 0 and np.isfinite(args.live_speed)):
        raise InputError(
            f"--live-speed must be >= 0 (0: as fast as it runs), got {args.live_speed}"
        )
    hub = LiveHub()
    server = LiveServer(create_app([], hub=hub), args.serve_port)
    out.print(f"live: {url_of('127.0.0.1', args.serve_port, None, '/live')}", markup=False)

    def simulator(scenario: Any, progress: Any = None) -> Any:
        steps = np.arange(scenario.n_steps + 1)
        return simulate_live(scenario, hub, steps, speed=args.live_speed, progress=progress)

    try:
        yield simulator
    finally:
        server.stop()
