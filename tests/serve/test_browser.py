"""The dashboard in a real browser: Chromium from the system, driven by Playwright.

The tests start the server (a free port) and then the browser, and stop both. Without
a system Chromium they are skipped with the reason on the summary line, unless
``FIREFLEET_REQUIRE_BROWSER=1`` (set by ``.ci/run``, which installs Chromium), where a
missing browser is a failure. ``FIREFLEET_SCREENSHOTS=DIR`` also saves the pages as PNGs.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from firefleet.serve.app import create_app
from firefleet.serve.live import LiveHub, simulate_live
from firefleet.serve.runs import find_runs
from tests.serve.conftest import Served, short

PALETTE = ["#d62728", "#1f77b4", "#2ca02c"]  # robots 1-3 in static/view.js
VIEWPORT = {"width": 1400, "height": 1000}


def chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        found = shutil.which(name)
        if found:
            return found
    return None


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    executable = chromium()
    if executable is None:
        reason = "no system Chromium (apt-get install chromium): the browser tests did not run"
        if os.environ.get("FIREFLEET_REQUIRE_BROWSER") == "1":
            pytest.fail(reason)
        pytest.skip(reason)
    from playwright.sync_api import sync_playwright

    args = ["--no-sandbox"] if hasattr(os, "geteuid") and os.geteuid() == 0 else []
    with sync_playwright() as playwright:
        launched = playwright.chromium.launch(executable_path=executable, args=args)
        yield launched
        launched.close()


@pytest.fixture
def page(browser: Any) -> Iterator[Any]:
    context = browser.new_context(viewport=VIEWPORT, device_scale_factor=1)
    opened = context.new_page()
    errors: list[str] = []
    opened.on("pageerror", lambda error: errors.append(str(error)))
    yield opened
    context.close()
    assert errors == []


def shoot(page: Any, name: str) -> None:
    folder = os.environ.get("FIREFLEET_SCREENSHOTS")
    if folder:
        page.screenshot(path=str(Path(folder) / name))


def canvas_pixels(page: Any, selector: str = "#scene") -> np.ndarray:
    png = page.locator(selector).screenshot()
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int32)


def centroid(pixels: np.ndarray, colour: str) -> np.ndarray:
    rgb = np.array([int(colour[i : i + 2], 16) for i in (1, 3, 5)])
    rows, cols = np.nonzero(np.abs(pixels - rgb).max(axis=2) <= 6)
    assert rows.size > 20, f"no robot drawn in {colour}"
    return np.array([cols.mean(), rows.mean()])


def open_run(page: Any, url: str, run_id: str) -> None:
    page.goto(f"{url}/run/{run_id}")
    page.wait_for_selector("body[data-ready='1']", timeout=30_000)


def only_robots(page: Any) -> None:
    page.evaluate(
        """() => { for (const box of document.querySelectorAll('#layers input')) {
             if (box.dataset.layer !== 'robots' && box.checked) box.click(); } }"""
    )


def set_slider(page: Any, value: str) -> None:
    page.evaluate(
        """(v) => { const s = document.getElementById('slider');
             s.value = v === 'max' ? s.max : v; s.dispatchEvent(new Event('input')); }""",
        value,
    )


def test_index_lists_the_runs(page: Any, served: Served, runs_root: Path) -> None:
    page.goto(served.url)
    page.wait_for_selector("body[data-ready='1']")
    rows = page.locator("#runs tbody tr")
    assert sorted(rows.evaluate_all("rs => rs.map(r => r.dataset.run)")) == sorted(
        p.name for p in runs_root.iterdir()
    )
    for run_dir in runs_root.iterdir():
        claims = json.loads((run_dir / "metrics.json").read_text())["claims"]
        cell = page.locator(f"tr[data-run='{run_dir.name}'] td.claims").inner_text()
        assert cell == f"{sum(c['passed'] for c in claims)} / {len(claims)}"
    shoot(page, "dashboard-index.png")


def test_the_canvas_draws_each_robot_at_its_recorded_final_pose(
    page: Any, served: Served, runs_root: Path
) -> None:
    open_run(page, served.url, "coop-different-paths")
    set_slider(page, "max")
    pixels = canvas_pixels(page)
    assert (np.abs(pixels - 255).max(axis=2) > 30).sum() > 2000  # not blank
    assert len({tuple(p) for p in pixels.reshape(-1, 3)[::7]}) > 20
    shoot(page, "dashboard-run.png")
    only_robots(page)
    pixels = canvas_pixels(page)
    view = page.evaluate("() => window.firefleet.view")
    with np.load(runs_root / "coop-different-paths" / "result.npz") as z:
        final = z["pose"][-1]
    for i, colour in enumerate(PALETTE):
        x, y = final[i, 0], final[i, 1]
        expected = np.array(
            [
                view["ox"] + (x - view["xmin"]) * view["scale"],
                view["oy"] + (view["ymax"] - y) * view["scale"],
            ]
        )
        assert np.abs(centroid(pixels, colour) - expected).max() <= 3.0, i
    # to scale: the robots' spacing on screen is their spacing in metres times one scale
    drawn = np.array([centroid(pixels, c) for c in PALETTE])
    metres = np.linalg.norm(final[0, :2] - final[2, :2])
    assert np.linalg.norm(drawn[0] - drawn[2]) == pytest.approx(metres * view["scale"], abs=4.0)


def test_play_moves_the_robots(page: Any, served: Served) -> None:
    open_run(page, served.url, "coop-different-paths")
    only_robots(page)
    set_slider(page, "0")
    before = centroid(canvas_pixels(page), PALETTE[2])
    page.select_option("#speed", "50")
    page.click("#play")
    page.wait_for_function("() => Number(document.getElementById('slider').value) > 200")
    page.click("#play")  # pause
    after = centroid(canvas_pixels(page), PALETTE[2])
    assert np.linalg.norm(after - before) > 20.0
    assert page.locator("#play").inner_text() == "play"


def test_the_claims_table_equals_metrics_json(page: Any, served: Served, runs_root: Path) -> None:
    for run_id in ("coop-different-paths", "formation-3", "motor-pid"):
        open_run(page, served.url, run_id)
        claims = json.loads((runs_root / run_id / "metrics.json").read_text())["claims"]
        rows = page.locator("#claims tbody tr").evaluate_all(
            """rs => rs.map(r => { const c = r.querySelectorAll('td');
                 return [c[0].textContent, c[1].textContent, JSON.parse(c[2].dataset.measured),
                         c[3].textContent, c[4].textContent]; })"""
        )
        expected = [
            [c["name"], c["expected"], c["measured"], "yes" if c["passed"] else "NO", c["source"]]
            for c in claims
        ]
        assert rows == expected


def test_the_live_page_receives_frames_while_the_run_simulates(page: Any) -> None:
    scenario = short("coop-different-paths", 12.0)
    hub = LiveHub()
    server = Served(create_app([], hub=hub))
    simulating = threading.Event()
    try:
        from firefleet.serve.scene import scene_of

        hub.set_hello({"type": "hello", "scenario": scenario.name, "scene": scene_of(scenario)})
        page.goto(f"{server.url}/live")
        page.wait_for_function("() => window.firefleetLive && window.firefleetLive.scene !== null")

        def run() -> None:
            simulating.set()
            simulate_live(scenario, hub, np.arange(scenario.n_steps + 1), speed=4.0)
            simulating.clear()

        worker = threading.Thread(target=run)
        worker.start()
        page.wait_for_function("() => window.firefleetLive.frames >= 10", timeout=30_000)
        assert simulating.is_set()  # ten frames drawn, and the run still going
        t_mid = page.evaluate("() => window.firefleetLive.last.t")
        assert 0.0 < t_mid < 12.0
        shoot(page, "dashboard-live.png")
        worker.join()
        page.wait_for_function("() => window.firefleetLive.finished", timeout=30_000)
        assert page.evaluate("() => window.firefleetLive.last.t") == 12.0
        pixels = canvas_pixels(page)
        for colour in PALETTE:
            centroid(pixels, colour)
    finally:
        server.stop()


def test_the_token_is_required_beyond_loopback(page: Any, runs_root: Path) -> None:
    token = "a-token-for-the-browser-test"
    server = Served(create_app(find_runs([runs_root]), token=token, loopback_only=False))
    try:
        assert page.goto(server.url).status == 401
        assert page.goto(f"{server.url}/run/motor-pid").status == 401
        assert page.goto(f"{server.url}/?token=wrong-{token}").status == 401
        assert page.goto(f"{server.url}/?token={token}").status == 200
        page.wait_for_selector("body[data-ready='1']")  # the page's own fetches pass (cookie)
        assert page.locator("#runs tbody tr").count() == 3
        open_run(page, server.url, "motor-pid")
        assert page.locator("#claims tbody tr").count() > 0
    finally:
        server.stop()


def test_sensor_layers_are_drawn_map_rays_thermal(page: Any, tmp_path: Path) -> None:
    from tests.serve.test_mcap import synthetic_run

    folder = tmp_path / "sensors"
    folder.mkdir()
    arrays = synthetic_run()
    np.savez_compressed(folder / "result.npz", **arrays)  # type: ignore[arg-type]
    (folder / "metrics.json").write_text(json.dumps({"scenario": "sensors", "claims": []}))
    server = Served(create_app(find_runs([folder])))
    try:
        open_run(page, server.url, "sensors")
        layers = page.locator("#layers input").evaluate_all("bs => bs.map(b => b.dataset.layer)")
        assert {"map", "ranges", "particles", "landmarks", "estimate:estimated_pose"} <= set(layers)
        set_slider(page, "max")
        shoot(page, "dashboard-sensors.png")
        assert page.locator("#thermal-panel").is_visible()
        image = page.evaluate(
            """() => { const c = document.getElementById('thermal');
                 const data = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
                 return [c.width, c.height, Array.from(data)]; }"""
        )
        width, height, rgba = image
        thermal = np.asarray(rgba).reshape(height, width, 4)[..., :3]
        frame = arrays["thermal_c"][-1, 0]  # robot 1's frame at the slider's end
        assert (width, height) == (8, 6)
        hot, cold = (
            np.unravel_index(frame.argmax(), frame.shape),
            np.unravel_index(frame.argmin(), frame.shape),
        )
        assert thermal[hot].tolist() == [255, 255, 255]  # the hottest cell white
        assert thermal[cold].tolist() == [0, 0, 0]  # the coldest black
        page.evaluate(  # the map alone
            """() => { for (const box of document.querySelectorAll('#layers input')) {
                 if (box.dataset.layer !== 'map' && box.checked) box.click(); } }"""
        )
        view = page.evaluate("() => window.firefleet.view")
        pixels = canvas_pixels(page)

        def px(x: float, y: float) -> tuple[int, int]:
            return (
                round(view["oy"] + (view["ymax"] - y) * view["scale"]),
                round(view["ox"] + (x - view["xmin"]) * view["scale"]),
            )

        # the map's top row (occupied) spans y = -2 + 40 * 0.1 = 2.0 m .. 1.9 m: black
        row, col = px(2.45, 1.95)  # (between the 1 m grid lines)
        assert pixels[row, col].max() < 60
        row, col = px(2.45, 1.45)  # a free cell: white
        assert pixels[row, col].min() > 200
        row, col = px(-1.5, 1.95)  # left of the map's origin: no map
        assert pixels[row, col].min() > 200
    finally:
        server.stop()
