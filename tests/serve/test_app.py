"""The dashboard's HTTP side: the index, a run's data, and who may read what."""

from __future__ import annotations

import json
import socket
import warnings
from pathlib import Path

import numpy as np
import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect
from websockets.typing import Origin

with warnings.catch_warnings():  # starlette 1.10 asks for httpx2; httpx works the same here
    warnings.simplefilter("ignore")
    from starlette.testclient import TestClient

from firefleet.cli._main import main
from firefleet.cli._serve import access
from firefleet.serve.app import create_app
from firefleet.serve.live import LiveHub
from firefleet.serve.runs import find_runs
from tests.serve.conftest import Served

TOKEN = "s3cret-token-for-tests"


def raw_get(port: int, target: str, host: str = "127.0.0.1") -> int:
    """The status of ``GET target`` sent byte for byte (no client normalises the path)."""
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(f"GET {target} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n".encode())
        head = s.recv(4096).decode("latin-1")
    return int(head.split()[1])


def test_index_lists_every_run_with_its_claims(runs_root: Path) -> None:
    client = TestClient(create_app(find_runs([runs_root])), base_url="http://127.0.0.1")
    runs = {r["id"]: r for r in client.get("/api/runs").json()}
    assert sorted(runs) == ["coop-different-paths", "formation-3", "motor-pid"]
    for run_id, run in runs.items():
        metrics = json.loads((runs_root / run_id / "metrics.json").read_text())
        assert run["claims_total"] == len(metrics["claims"])
        assert run["claims_passed"] == sum(c["passed"] for c in metrics["claims"])
        assert run["seed"] == metrics["provenance"]["seed"]
        assert run["replay"] == "result.npz"


def test_run_document_holds_the_recorded_poses_and_layers(runs_root: Path) -> None:
    client = TestClient(create_app(find_runs([runs_root])), base_url="http://127.0.0.1")
    doc = client.get("/api/run/coop-different-paths").json()
    with np.load(runs_root / "coop-different-paths" / "result.npz") as z:
        pose, t, y_err = z["pose"], z["t"], z["y_err_m"]
    drawn = doc["layers"]
    assert drawn["t"][0] == t[0]
    assert drawn["t"][-1] == t[-1]
    np.testing.assert_allclose(drawn["pose"][-1], pose[-1], atol=1e-4)
    np.testing.assert_allclose(drawn["pose"][0], pose[0], atol=1e-4)
    assert set(drawn["points"]) == {"desired_xy_m"}
    assert set(drawn["estimates"]) == {"odometry_pose"}
    assert len(drawn["scene"]["paths"]) == 3
    # the scene's paths start where the robots start (the scenario's poses)
    starts = np.array([p[0] for p in drawn["scene"]["paths"]])
    np.testing.assert_allclose(starts, pose[0, :, :2], atol=1e-3)
    k = len(drawn["t"]) // 2
    index = int(np.searchsorted(t, drawn["t"][k]))
    np.testing.assert_allclose(drawn["series"]["y_err_m"][k], y_err[index], atol=1e-4)
    formation = client.get("/api/run/formation-3").json()["layers"]
    assert formation["scene"]["formation_radius_m"] == 3.0
    assert set(formation["points"]) == {"leader_xy_m", "formation_xy_m"}


# every way of naming a file outside the run table: literal, encoded, doubly encoded,
# absolute, backslashes
TRAVERSALS = [
    "/../../../../etc/passwd",
    "/static/../runs.py",
    "/static/..%2fapp.py",
    "/static/%2e%2e/app.py",
    "/static/%2e%2e%2fapp.py",
    "/static/%252e%252e%252fapp.py",
    "/static//etc/passwd",
    "/static/%2fetc%2fpasswd",
    "/run/..%2f..%2fetc%2fpasswd",
    "/run/coop-different-paths/../../../etc/passwd",
    "/api/run/..",
    "/api/run/%2e%2e",
    "/api/run/coop-different-paths/file/..%2fformation-3%2fmetrics.json",
    "/api/run/coop-different-paths/file/%2e%2e%2f%2e%2e%2fetc%2fpasswd",
    "/api/run/coop-different-paths/file/%2fetc%2fpasswd",
    "/api/run/coop-different-paths/file/..%5c..%5cmetrics.json",
    "/api/run/coop-different-paths/file/metrics.json",
    "/api/run/coop-different-paths/file/result.npz",
    "//etc/passwd",
    "/etc/passwd",
]


@pytest.mark.parametrize("target", TRAVERSALS)
def test_path_traversal_is_404(served: Served, target: str) -> None:
    assert raw_get(served.port, target) == 404


def test_what_is_served_is_200(served: Served, runs_root: Path) -> None:
    for target in ("/", "/run/motor-pid", "/static/run.js", "/api/run/formation-3"):
        assert raw_get(served.port, target) == 200, target


def test_nothing_writes_or_deletes(runs_root: Path) -> None:
    before = sorted(p.as_posix() for p in runs_root.rglob("*"))
    client = TestClient(create_app(find_runs([runs_root])), base_url="http://127.0.0.1")
    for path in ("/", "/api/runs", "/api/run/motor-pid", "/run/motor-pid", "/static/run.js"):
        for method in ("POST", "PUT", "DELETE", "PATCH"):
            assert client.request(method, path).status_code == 405, (method, path)
    assert sorted(p.as_posix() for p in runs_root.rglob("*")) == before


def test_beyond_loopback_every_request_needs_the_token(runs_root: Path) -> None:
    assert access("127.0.0.1", None) == (None, True)
    generated, loopback_only = access("0.0.0.0", None)
    assert generated is not None
    assert len(generated) >= 20
    assert not loopback_only
    assert access("192.168.1.5", TOKEN) == (TOKEN, False)
    app = create_app(find_runs([runs_root]), token=TOKEN, loopback_only=False, hub=LiveHub())
    client = TestClient(app, base_url="http://robot.lan:8000")
    for path in ("/", "/api/runs", "/api/run/motor-pid", "/static/run.js", "/live"):
        assert client.get(path).status_code == 401, path
        assert client.get(path, params={"token": "wrong-token"}).status_code == 401
        assert client.get(path, headers={"Authorization": f"Bearer {TOKEN}"}).status_code == 200
    first = client.get("/", params={"token": TOKEN})
    assert first.status_code == 200
    assert "HttpOnly" in first.headers["set-cookie"]
    assert client.get("/api/runs").status_code == 200  # the cookie the link set
    served = Served(app)
    try:
        uri = f"ws://127.0.0.1:{served.port}/ws/live"
        with pytest.raises(InvalidStatus, match="403"):  # a refused handshake is 403
            connect(uri).close()
        with pytest.raises(InvalidStatus, match="403"):
            connect(uri + "?token=wrong-token").close()
        with connect(uri + f"?token={TOKEN}") as ws:
            assert json.loads(ws.recv(timeout=10)) == {}
    finally:
        served.stop()


def test_websocket_from_a_foreign_origin_is_refused() -> None:
    hub = LiveHub()
    hub.set_hello({"type": "hello"})
    served = Served(create_app([], hub=hub))
    try:
        uri = f"ws://127.0.0.1:{served.port}/ws/live"
        with pytest.raises(InvalidStatus, match="403"):
            connect(uri, origin=Origin("http://evil.example")).close()
        with pytest.raises(InvalidStatus, match="403"):  # same host, another port
            connect(uri, origin=Origin(f"http://127.0.0.1:{served.port + 1}")).close()
        with connect(uri, origin=Origin(f"http://127.0.0.1:{served.port}")) as ws:
            assert json.loads(ws.recv(timeout=10)) == {"type": "hello"}
    finally:
        served.stop()


def test_loopback_server_refuses_foreign_host_names() -> None:
    client = TestClient(create_app([]), base_url="http://attacker.example")  # DNS rebinding
    assert client.get("/api/runs").status_code == 403
    for host in ("http://localhost:8000", "http://127.0.0.1", "http://[::1]:8000"):
        assert TestClient(create_app([]), base_url=host).get("/api/runs").status_code == 200


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["serve", "NO-SUCH-FOLDER"], "RUN_DIR NO-SUCH-FOLDER: no such folder"),
        (["serve", "NO-SUCH-FOLDER", "--port", "0"], "--port must be 1..65535, got 0"),
        (
            ["serve", "NO-SUCH-FOLDER", "--host", "0.0.0.0", "--token", "short"],
            "--token must be at least",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    argv: list[str], said: str, capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert said in err
    assert len(err.strip().splitlines()) == 1


def test_serve_without_folders_needs_a_runs_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["serve"]) == 2
    assert "RUN_DIR: none given and no runs/ folder here" in capsys.readouterr().err


def test_a_folder_without_runs_is_bad_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "empty").mkdir()
    assert main(["serve", str(tmp_path / "empty")]) == 2
    assert "holds no run folder" in capsys.readouterr().err
