"""The dashboard: runs in a browser, replayed or live (``firefleet serve``, ``run --live``).

- :mod:`.runs`: the run folders served, found by id, never by a path from a request;
- :mod:`.replay`: a run's arrays as layers, found by name and shape;
- :mod:`.scene`: a scenario's static geometry (paths, obstacles, the formation circle);
- :mod:`.security`: the token, the Host and the websocket Origin;
- :mod:`.live`: a running simulation's poses to the browser, frames dropped, never waited for;
- :mod:`.app`: the Starlette app; ``static/``: its HTML, JS and CSS (no CDN).
"""
