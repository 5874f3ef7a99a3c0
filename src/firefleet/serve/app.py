"""The dashboard's web app (Starlette): the index, the run pages, their data, live frames.

Starlette rather than FastAPI: the app has six read-only routes and no request bodies,
so FastAPI's models and its generated ``/docs`` pages would add surface and nothing
used; FastAPI is Starlette underneath, on the same uvicorn server.

Routes (all ``GET``; nothing writes or deletes):

=================================  ==================================================
``/``                              the index of runs (``static/index.html``)
``/run/{id}``                      a run page (``static/run.html``)
``/live``                          the live page (when a run streams)
``/static/{name}``                 the package's JS and CSS, by name from a fixed list
``/api/runs``                      the runs' summaries (JSON)
``/api/run/{id}``                  a run's summary, ``metrics.json``, figures and layers
``/api/run/{id}/file/{name}``      a PNG figure the run's folder holds
``/ws/live``                       live frames (websocket)
=================================  ==================================================

A run is found by its id in a table made when the server starts; no part of a URL is
ever joined to a path, so ``/../``, absolute paths and their URL-encoded forms are 404.
"""

from __future__ import annotations

import asyncio
import json
from importlib import resources
from typing import Any

import numpy as np
from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, Response
from starlette.routing import Route, WebSocketRoute
from starlette.websockets import WebSocket, WebSocketDisconnect

from firefleet.serve.live import LiveHub
from firefleet.serve.replay import layers
from firefleet.serve.runs import RunFolder, read_json, run_summary
from firefleet.serve.scene import scene_of_name
from firefleet.serve.security import Guard

__all__ = ["STATIC_TYPES", "create_app", "run_document"]

STATIC_TYPES = {".js": "text/javascript", ".css": "text/css", ".html": "text/html"}


def _static_files() -> dict[str, bytes]:
    """The package's ``static/`` files by name (read once)."""
    folder = resources.files("firefleet.serve") / "static"
    return {
        entry.name: entry.read_bytes()
        for entry in folder.iterdir()
        if entry.is_file() and any(entry.name.endswith(s) for s in STATIC_TYPES)
    }


def _arrays(run: RunFolder) -> dict[str, np.ndarray] | None:
    npz = run.file("result.npz")
    if npz is not None:
        with np.load(npz, allow_pickle=False) as archive:
            return {name: archive[name] for name in archive.files}
    mcap = run.file("run.mcap")
    if mcap is not None:
        from firefleet.mcap_log import read_mcap

        return read_mcap(mcap.read_bytes())
    return None


def run_document(run: RunFolder) -> dict[str, Any]:
    """Everything a run page shows: summary, ``metrics.json``, figures, drawn layers.

    ``layers`` is None for a run without arrays (the thermal, stereo and SLAM report
    runs show their claims and figures).
    """
    metrics = read_json(run.file("metrics.json"))
    figures = sorted(p.name for p in run.path.glob("*.png") if run.file(p.name))
    arrays = _arrays(run)
    drawn = None
    if arrays is not None and "t" in arrays and "pose" in arrays:
        drawn = layers(arrays, scene_of_name(str(metrics.get("scenario", ""))))
    return {"summary": run_summary(run), "metrics": metrics, "figures": figures, "layers": drawn}


def _json(document: Any) -> Response:
    text = json.dumps(document, separators=(",", ":"), allow_nan=False)
    return Response(text, media_type="application/json")


def create_app(
    runs: list[RunFolder],
    *,
    token: str | None = None,
    loopback_only: bool = True,
    hub: LiveHub | None = None,
) -> Guard:
    """The dashboard as an ASGI app.

    Parameters
    ----------
    runs : list of RunFolder
        The runs it serves (:func:`firefleet.serve.runs.find_runs`).
    token : str, optional
        Required on every request when given (:mod:`firefleet.serve.security`).
    loopback_only : bool
        Accept only requests naming a loopback host (the server is bound to one).
    hub : LiveHub, optional
        The live run's frames (``firefleet run --live``); None: no live page.

    Examples
    --------
    >>> from firefleet.serve.app import create_app
    >>> app = create_app([], token="a-long-token")
    >>> type(app).__name__, app.token, app.loopback_only
    ('Guard', 'a-long-token', True)
    """
    by_id = {run.run_id: run for run in runs}
    static = _static_files()
    cache: dict[str, Response] = {}

    def page(name: str) -> Response:
        return Response(static[name], media_type="text/html; charset=utf-8")

    def find(request: Request) -> RunFolder:
        run = by_id.get(request.path_params["run_id"])
        if run is None:
            raise HTTPException(404)
        return run

    async def index(request: Request) -> Response:
        return page("index.html")

    async def run_page(request: Request) -> Response:
        find(request)
        return page("run.html")

    async def live_page(request: Request) -> Response:
        if hub is None:
            raise HTTPException(404)
        return page("live.html")

    async def static_file(request: Request) -> Response:
        name = request.path_params["name"]
        if name not in static:
            raise HTTPException(404)
        suffix = name[name.rfind(".") :]
        return Response(static[name], media_type=STATIC_TYPES[suffix])

    async def api_runs(request: Request) -> Response:
        return JSONResponse([run_summary(run) for run in runs])

    async def api_run(request: Request) -> Response:
        run = find(request)
        if run.run_id not in cache:
            document = await asyncio.to_thread(run_document, run)
            cache[run.run_id] = _json(document)
        return cache[run.run_id]

    async def api_file(request: Request) -> Response:
        run = find(request)
        name = request.path_params["name"]
        path = run.file(name) if name.endswith(".png") else None
        if path is None:
            raise HTTPException(404)
        return FileResponse(path, media_type="image/png")

    async def live_socket(websocket: WebSocket) -> None:
        if hub is None:
            await websocket.close(code=1008)
            return
        await websocket.accept()
        await websocket.send_text(hub.hello())
        seq = 0
        closed = asyncio.ensure_future(websocket.receive())  # the page says nothing but bye
        try:
            while True:
                newer = asyncio.ensure_future(hub.frames(seq))
                await asyncio.wait({newer, closed}, return_when=asyncio.FIRST_COMPLETED)
                if closed.done():
                    newer.cancel()
                    return
                seq, text = newer.result()
                await websocket.send_text(text)
        except (WebSocketDisconnect, RuntimeError):
            return
        finally:
            closed.cancel()

    async def not_found(request: Request, exc: Exception) -> Response:
        status = exc.status_code if isinstance(exc, HTTPException) else 500
        return Response("not found" if status == 404 else "error", status_code=status)

    app = Starlette(
        routes=[
            Route("/", index),
            Route("/run/{run_id}", run_page),
            Route("/live", live_page),
            Route("/static/{name}", static_file),
            Route("/api/runs", api_runs),
            Route("/api/run/{run_id}", api_run),
            Route("/api/run/{run_id}/file/{name}", api_file),
            WebSocketRoute("/ws/live", live_socket),
        ],
        exception_handlers={HTTPException: not_found},
    )
    return Guard(app=app, token=token, loopback_only=loopback_only)
