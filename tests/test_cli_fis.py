"""``firefleet fis``: tables and plots, --eval on a CSV, line-numbered errors (exit 2)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from firefleet.cli import main
from firefleet.control.fuzzy import evaluate, read_fis
from firefleet.report.fuzzy import surface_grid

DATA = Path(__file__).resolve().parent / "data" / "fuzzy"
FIS = DATA / "matlab_v2_sugeno.fis"
PNG = b"\x89PNG\r\n\x1a\n"


def test_fis_prints_tables_and_writes_plots(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "plots"
    assert main(["fis", str(FIS), "--out", str(out), "--fix", "angle=0.25"]) == 0
    text = capsys.readouterr().out
    for expected in ("input dist", "output turn", "dist is near", "angle is not left", "0.5"):
        assert expected in text
    names = sorted(p.name for p in out.glob("[!.]*"))
    assert names == [
        "mf_angle.png",
        "mf_dist.png",
        "surface_speed_dist_angle.png",
        "surface_turn_dist_angle.png",
    ]
    assert all((out / n).read_bytes()[:8] == PNG for n in names)
    assert not list(tmp_path.glob(".plots.staging-*"))


def test_surface_grid_holds_other_inputs_and_matches_evaluate() -> None:
    system = read_fis(DATA / "matlab_legacy_sugeno.fis")
    X, Y, Z = surface_grid(system, "u", "e", "de", points=5)
    assert X.shape == Y.shape == Z.shape == (5, 5)
    expected = evaluate(system, np.column_stack([X.ravel(), Y.ravel()]))[:, 0]
    np.testing.assert_array_equal(Z.ravel(), expected)
    np.testing.assert_array_equal(X[0], np.linspace(-2, 2, 5))  # the input's range


def test_fis_eval_csv(tmp_path: Path) -> None:
    src = tmp_path / "in.csv"
    src.write_text("angle,dist\n0.5,1.5\n-1,3.5\n")
    dest = tmp_path / "out.csv"
    assert main(["fis", str(FIS), "--eval", str(src), "--out", str(dest)]) == 0
    rows = dest.read_text().splitlines()
    assert rows[0] == "speed,turn"
    got = np.array([[float(v) for v in r.split(",")] for r in rows[1:]])
    # hand values of tests/control/test_fuzzy.py::test_matlab_v2_file_hand_values
    np.testing.assert_allclose(got, [[0.096875 / 0.375, 0.5], [0.875, -1.0]], rtol=0, atol=1e-12)


def test_fis_eval_missing_column_exits_2_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "in.csv"
    src.write_text("dist,heading\n1,2\n")
    dest = tmp_path / "out.csv"
    assert main(["fis", str(FIS), "--eval", str(src), "--out", str(dest)]) == 2
    err = capsys.readouterr().err
    assert f"{src}:1: column 'heading' is not an input" in err
    assert "Traceback" not in err
    assert not dest.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.csv"]


def test_fis_bad_file_exits_2_with_line_number(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.fis"
    bad.write_text(
        FIS.read_text().replace("MF2='far':'trapmf',[1 3 4 4]", "MF2='far':'trapmf',[1 3]")
    )
    out = tmp_path / "o"
    assert main(["fis", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"firefleet: error: {bad}:19: MF2:")
    assert "trapmf takes 4 parameters" in err[0]
    assert not out.exists()


def test_fis_mamdani_file_is_rejected(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    mamdani = tmp_path / "m.fis"
    mamdani.write_text(FIS.read_text().replace("Type='sugeno'", "Type='mamdani'"))
    assert main(["fis", str(mamdani), "--out", str(tmp_path / "o")]) == 2
    assert f"{mamdani}:3: Type='mamdani': only Sugeno" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--fix", "heading=1"], "unknown input 'heading'"),
        (["--fix", "dist"], "--fix dist: expected NAME=VALUE"),
        (["--eval", "in.csv"], "--eval IN.csv needs --out OUT.csv"),
    ],
)
def test_fis_bad_options_exit_2(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    extra: list[str],
    message: str,
) -> None:
    monkeypatch.chdir(tmp_path)  # the default output folder is relative
    shutil.copy(FIS, tmp_path / "c.fis")
    assert main(["fis", str(tmp_path / "c.fis"), *extra]) == 2
    assert message in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.fis"]


def test_fis_range_beyond_float_resolution_exits_2_before_printing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Range=[0 1e308] printed the tables, then crashed in matplotlib (arange)
    big = tmp_path / "big.fis"
    big.write_text(FIS.read_text().replace("Range=[0 4]", "Range=[0 1e308]"))
    out = tmp_path / "o"
    assert main(["fis", str(big), "--out", str(out)]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"firefleet: error: {big}:16: [Input1] Range=[0 1e308]: ")
    assert "within +-1e+15" in err[0]
    assert "Traceback" not in captured.err
    assert captured.out == ""  # no tables printed first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.fis"]


def test_fis_eval_into_an_existing_folder_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src = tmp_path / "in.csv"
    src.write_text("angle,dist\n0.5,1.5\n")
    folder = tmp_path / "results"
    folder.mkdir()
    assert main(["fis", str(FIS), "--eval", str(src), "--out", str(folder)]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"firefleet: error: --out {folder}: is a folder")
    assert "Traceback" not in captured.err
    assert list(folder.iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.csv", "results"]


@pytest.mark.parametrize(
    ("setup", "message"),
    [
        ("missing", "no such file"),
        ("folder", "is a folder, not a CSV file"),
        ("binary", "not UTF-8 text"),
    ],
)
def test_fis_eval_unreadable_input_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], setup: str, message: str
) -> None:
    src = tmp_path / "in.csv"
    if setup == "folder":
        src.mkdir()
    elif setup == "binary":
        src.write_bytes(b"\xff\xfe\x00dist")
    dest = tmp_path / "out.csv"
    assert main(["fis", str(FIS), "--eval", str(src), "--out", str(dest)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"firefleet: error: --eval {src}: {message}"), err[0]
    assert not dest.exists()


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(data=st.binary(max_size=200), as_csv=st.booleans())
def test_fis_random_bytes_exit_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], data: bytes, as_csv: bool
) -> None:
    """Random bytes as the .fis file or as the --eval table: one line, exit 2."""
    bad = tmp_path / ("in.csv" if as_csv else "r.fis")
    bad.write_bytes(data)
    dest = tmp_path / "out.csv"
    fis = FIS if as_csv else bad
    capsys.readouterr()
    code = main(["fis", str(fis), "--eval", str(bad if as_csv else FIS), "--out", str(dest)])
    err = capsys.readouterr().err
    if as_csv and code == 0:  # random bytes can be a valid table only by chance
        return
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1, err
    assert "Traceback" not in err
    assert not dest.exists()
