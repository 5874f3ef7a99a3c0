"""MATLAB ``.fis`` text and CSV tables: reading, writing, line-numbered errors.

References: hand-written MATLAB-style files (Version 2.0 and the older layout) with
hand-computed outputs, and round trips through our own writer.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from firefleet.control.fuzzy import (
    FuzzyInput,
    MembershipFunction,
    SugenoSystem,
    evaluate,
    evaluate_csv,
    fis_text,
    parse_fis,
    read_fis,
)
from firefleet.errors import InputError
from tests.control.fuzzy_systems import every_feature, systems

DATA = Path(__file__).resolve().parents[1] / "data" / "fuzzy"

EXACT = 1e-12
"""Same closed form in float64 on both sides: only rounding (~1e-16) may differ."""


# ------------------------------------------------------------------ .fis files


def test_round_trip_write_read_same_outputs(tmp_path: Path) -> None:
    system = every_feature()
    path = tmp_path / "every.fis"
    path.write_text(fis_text(system), encoding="utf-8")
    again = read_fis(path)
    assert again == system
    x = np.random.default_rng(5).uniform(-4, 6, size=(200, 3))
    np.testing.assert_allclose(evaluate(again, x), evaluate(system, x), rtol=0, atol=EXACT)
    assert [p.name for p in tmp_path.iterdir()] == ["every.fis"]  # no temporary left


@settings(max_examples=80, deadline=None)
@given(systems())
def test_fis_text_round_trip_property(system: SugenoSystem) -> None:
    assert parse_fis(fis_text(system)) == system


def test_matlab_v2_file_hand_values() -> None:
    system = read_fis(DATA / "matlab_v2_sugeno.fis")
    assert [v.name for v in system.inputs] == ["dist", "angle"]
    assert system.rules[1].weight == 0.5
    assert system.rules[3].antecedent == (0, -1)
    # (1.5, 0.5): near = far = 0.25, left = 0.25, not left = 0.75
    #   speed = (0.25 * 0.2 + 0.5 * 0.25 * (0.25 * 1.5)) / (0.25 + 0.125); turn = 0.5
    # (3.5, -1): far = 1, left = 1: speed = 0.25 * 3.5, turn = -1
    # (10, 5) is clipped to (4, 1): speed = 0.25 * 4 (linear sees the clipped input), turn = 1
    x = np.array([[1.5, 0.5], [3.5, -1.0], [10.0, 5.0]])
    expected = [[0.096875 / 0.375, 0.5], [0.875, -1.0], [1.0, 1.0]]
    np.testing.assert_allclose(evaluate(system, x), expected, rtol=0, atol=EXACT)
    # written back in MATLAB's layout, it is the same file (numbers and all)
    assert fis_text(system) == (DATA / "matlab_v2_sugeno.fis").read_text()


def test_matlab_legacy_file_hand_values() -> None:
    system = read_fis(DATA / "matlab_legacy_sugeno.fis")
    assert system.inputs[0].mfs[0].params == (1.0, 2.0, -1.0)  # padding dropped
    assert system.outputs[0].mfs[1].params == (-1.0,)
    assert system.outputs[0].range == (0.0, 0.0)
    assert (system.and_method, system.or_method, system.defuzz) == ("min", "max", "wtsum")
    # (0, 0): every MF is 1/2; rule 1 (min) 0.5 * z(0, 0) = 0; rule 2 (max) 0.5 * -1
    # (1, 0.25): low = 1/17, high = 1, rising = 1/(1 + e^-1), falling = 1/(1 + e):
    #   rule 1 = min(1/17, rising) * (1 + 0.5 * 0.25); rule 2 = max(1, falling) * -1
    x = np.array([[0.0, 0.0], [1.0, 0.25]])
    expected = [[-0.5], [1.125 / 17 - 1.0]]
    np.testing.assert_allclose(evaluate(system, x), expected, rtol=0, atol=EXACT)


GOOD = (DATA / "matlab_v2_sugeno.fis").read_text()


def _edit(old: str, new: str) -> str:
    assert old in GOOD
    return GOOD.replace(old, new, 1)


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("", 1, "missing [System] section"),
        (GOOD.replace("[System]", "[Sistem]"), 1, "unknown section [Sistem]"),
        (_edit("Type='sugeno'", "Type='mamdani'"), 3, "only Sugeno"),
        (
            GOOD[: GOOD.index("[Input2]")] + GOOD[GOOD.index("[Output1]") :],
            5,
            "no [Input2] section",
        ),
        (_edit("[Input2]", "[Input3]"), 21, "[Input3] but NumInputs=2"),
        (GOOD[: GOOD.index("[Rules]")], 7, "NumRules=4 but there is no [Rules] section"),
        (_edit("Range=[0 4]", "Range=[0 4x]"), 16, "bad number '4x'"),
        (_edit("Range=[0 4]", "Range=[4 0]"), 16, "min <= max"),
        (_edit("MF1='near':'trimf',[0 0 2]", "MF1='near':'trimf',[0 2]"), 18, "takes 3 parameters"),
        (_edit("MF1='near':'trimf',[0 0 2]", "MF1='near':'trimf',[2 0 4]"), 18, "a <= b <= c"),
        (
            _edit("MF1='near':'trimf'", "MF1='near':'cosmf'"),
            18,
            "unknown membership function type 'cosmf'",
        ),
        (
            _edit("MF1='near':'trimf',[0 0 2]", "MF1=near trimf 0 0 2"),
            18,
            "expected 'name':'type',[params]",
        ),
        (_edit("NumMFs=2\nMF1='near'", "NumMFs=3\nMF1='near'"), 17, "missing MF3"),
        (
            _edit("MF1='slow':'constant',[0.2]", "MF1='slow':'trimf',[0 1 2]"),
            32,
            "'constant' or 'linear'",
        ),
        (
            _edit("MF2='fast':'linear',[0.25 0 0]", "MF2='fast':'linear',[0.25 1]"),
            33,
            "takes 3 parameter",
        ),
        (
            _edit("1 0, 1 0 (1) : 1", "3 0, 1 0 (1) : 1"),
            43,
            "input 1 ('dist') has no membership function 3",
        ),
        (
            _edit("1 0, 1 0 (1) : 1", "1 0, 1 5 (1) : 1"),
            43,
            "output 2 ('turn') has no membership function 5",
        ),
        (_edit("1 0, 1 0 (1) : 1", "1 0 0, 1 0 (1) : 1"), 43, "3 antecedent indices for 2 inputs"),
        (
            _edit("1 0, 1 0 (1) : 1", "1 0, 1 0 (1.5) : 1"),
            43,
            "weight must be one number in [0, 1]",
        ),
        (_edit("1 0, 1 0 (1) : 1", "1 0, 1 0 (1) : 3"), 43, "connective must be 1 (AND) or 2 (OR)"),
        (_edit("1 0, 1 0 (1) : 1", "1.2 0, 1 0 (1) : 1"), 43, "hedges are not supported"),
        (_edit("NumRules=4", "NumRules=5"), 7, "NumRules=5 but [Rules] (line 42) has 4 rule(s)"),
        (_edit("AndMethod='prod'", "AndMethod='mymin'"), 8, "AndMethod 'mymin' is not supported"),
        (_edit("Version=2.0", "Version=3.0"), 4, "only .fis versions 1.0 and 2.0"),
        (_edit("Name='dist'", "Nme='dist'"), 15, "unknown key 'Nme' in [Input1]"),
        # a bare MF key (found by the mutation test below; it raised ValueError)
        (_edit("MF2='far'", "MF='far'"), 19, "unknown key 'MF' in [Input1]"),
        # a huge count (found by fuzzing; it raised OverflowError or MemoryError)
        (_edit("NumMFs=2\nMF1='near'", "NumMFs=1e308\nMF1='near'"), 17, "missing MF3"),
        (_edit("NumMFs=2\nMF1='near'", "NumMFs=51e15\nMF1='near'"), 17, "missing MF3"),
        (_edit("NumInputs=2", "NumInputs=two"), 5, "NumInputs must be a whole number"),
    ],
)
def test_malformed_fis_names_the_line(text: str, line: int, message: str) -> None:
    with pytest.raises(InputError) as info:
        parse_fis(text, origin="bad.fis")
    assert str(info.value).startswith(f"bad.fis:{line}: "), str(info.value)
    assert message in str(info.value)


def test_variants_matlab_tolerates() -> None:
    # rule lines without the comma, without weight and connective; '#' comments; CRLF
    text = (
        GOOD.replace("1 0, 1 0 (1) : 1", "1 0 1 0")
        .replace("0 1, 0 1 (1) : 1", "0 1 0 1 (1) : 1")
        .replace("[Input1]", "# a comment\n[Input1]")
        .replace("\n", "\r\n")
    )
    assert parse_fis(text) == parse_fis(GOOD)


def test_read_fis_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such file"):
        read_fis(tmp_path / "absent.fis")


# ------------------------------------------------------------------ CSV


def test_evaluate_csv_columns_by_name() -> None:
    system = read_fis(DATA / "matlab_v2_sugeno.fis")
    table = evaluate_csv(system, "angle,dist\n0.5,1.5\n-1,3.5\n")
    lines = table.splitlines()
    assert lines[0] == "speed,turn"
    got = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    np.testing.assert_allclose(got, [[0.096875 / 0.375, 0.5], [0.875, -1.0]], rtol=0, atol=EXACT)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "in.csv:1: empty file"),
        ("dist\n1\n", "in.csv:1: missing column 'angle'"),
        ("dist,angle,extra\n1,2,3\n", "in.csv:1: column 'extra' is not an input"),
        ("dist,angle\n", "in.csv:1: no data rows"),
        ("dist,angle\n1,x\n", "in.csv:2: column 'angle': bad number 'x'"),
        ("dist,angle\n1,2\n1\n", "in.csv:3: 1 fields, the header has 2"),
        ("dist,angle\n1,nan\n", "in.csv:2: column 'angle': nan is not finite"),
    ],
)
def test_evaluate_csv_errors(text: str, message: str) -> None:
    system = read_fis(DATA / "matlab_v2_sugeno.fis")
    with pytest.raises(InputError) as info:
        evaluate_csv(system, text, origin="in.csv")
    assert message in str(info.value)


# ------------------------------------------------------------------ ranges and the README


@pytest.mark.parametrize("value", ["[0 1e308]", "[-1e16 0]", "[-2e15 2e15]"])
def test_fis_range_beyond_float_resolution_names_file_line_and_key(value: str) -> None:
    # Range=[0 1e308] used to be read, then crash the plots (matplotlib's arange)
    with pytest.raises(InputError) as info:
        parse_fis(_edit("Range=[0 4]", f"Range={value}"), origin="big.fis")
    message = str(info.value)
    assert message.startswith("big.fis:16: [Input1] Range=" + value), message
    assert "within +-1e+15" in message


def test_fis_range_at_the_limit_is_accepted() -> None:
    system = parse_fis(_edit("Range=[0 4]", "Range=[-1e15 1e15]"))
    assert system.inputs[0].range == (-1e15, 1e15)
    with pytest.raises(InputError, match=r"input 'x': range ends must lie within \+-1e\+15"):
        FuzzyInput("x", (0, 1e308), (MembershipFunction("a", "trimf", (0, 1, 2)),))


def test_readme_fuzzy_example_runs_as_printed(capsys: pytest.CaptureFixture[str]) -> None:
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    anchor = readme.index("from firefleet.control.fuzzy import evaluate, read_fis")
    start = readme.rindex("```python\n", 0, anchor) + len("```python\n")
    code = readme[start : readme.index("```", start)]
    namespace: dict[str, object] = {}
    exec(compile(code, "README.md", "exec"), namespace)
    v_omega = namespace["v_omega"]
    assert isinstance(v_omega, np.ndarray)
    assert v_omega.shape == (2, 2)
    np.testing.assert_array_equal(namespace["one"], v_omega[0])
    assert "['D_rp', 'x_err', 'alpha']" in capsys.readouterr().out


@st.composite
def _mutated_fis(draw: st.DrawFn) -> str:
    """The good file with a few random edits: deleted, replaced or inserted text."""
    text = GOOD
    for _ in range(draw(st.integers(1, 4))):
        at = draw(st.integers(0, len(text)))
        cut = draw(st.integers(0, 12))
        new = draw(
            st.one_of(
                st.text(max_size=8),
                st.sampled_from(
                    [
                        "1e308",
                        "-1e400",
                        "nan",
                        "inf",
                        "0",
                        "-1",
                        "[",
                        "]",
                        "'",
                        ",",
                        ":",
                        "\n",
                        "=",
                        "(",
                        ")",
                        "2.5",
                        "[Input3]",
                    ]
                ),
            )
        )
        text = text[:at] + new + text[at + cut :]
    return text


@settings(max_examples=300, deadline=None)
@given(_mutated_fis())
def test_mutated_fis_text_is_read_or_rejected_with_input_error(text: str) -> None:
    """Random edits of a valid file: a valid system or one InputError with file and
    line, never another exception; what is read evaluates to finite numbers."""
    system: SugenoSystem | None = None
    message = ""
    try:
        system = parse_fis(text, origin="m.fis")
    except InputError as exc:
        message = str(exc)
    if system is None:
        assert message.startswith("m.fis:"), message
        assert "\n" not in message.strip()
        return
    x = np.array([[v.range[0], v.range[1]][k % 2] for k, v in enumerate(system.inputs)])
    assert np.all(np.isfinite(evaluate(system, x)))
    assert parse_fis(fis_text(system)) == system


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=300))
def test_random_bytes_are_rejected_with_input_error(
    tmp_path_factory: pytest.TempPathFactory, data: bytes
) -> None:
    path = tmp_path_factory.mktemp("fis") / "r.fis"
    path.write_bytes(data)
    with pytest.raises(InputError) as info:
        read_fis(path)
    assert str(info.value).startswith(f"{path}:")
