"""MATLAB ``.fis`` text: the reader (:func:`parse_fis`, :func:`read_fis`) and the writer
(:func:`fis_text`, which returns the text; the command line writes files).

Reads what MATLAB's ``writefis`` writes (Version 2.0) and the older files shipped with
the toolbox; writes Version 2.0, so a controller designed in MATLAB loads as it is and
ours opens there. Only Sugeno systems are read.

References
----------
MathWorks, Fuzzy Logic Toolbox User's Guide: ``readfis``, ``writefis``.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import NoReturn

from firefleet.control.fuzzy._membership import MF_KINDS, N_PARAMS
from firefleet.control.fuzzy._system import (
    AND_METHODS,
    DEFUZZ_METHODS,
    OR_METHODS,
    FuzzyInput,
    FuzzyOutput,
    MembershipFunction,
    Rule,
    SugenoOutputMf,
    SugenoSystem,
    range_problem,
)
from firefleet.errors import InputError

__all__ = ["fis_text", "parse_fis", "read_fis"]

logger = logging.getLogger(__name__)


def _num(v: float) -> str:
    """Shortest text that reads back to the same float (integers without '.0')."""
    if v.is_integer() and abs(v) < 1e15:
        return str(int(v))
    return repr(v)


def _nums(values: Sequence[float]) -> str:
    return "[" + " ".join(_num(v) for v in values) + "]"


def fis_text(system: SugenoSystem) -> str:
    """The system as MATLAB ``.fis`` text (``writefis``'s Version 2.0 layout).

    Numbers are written with the shortest representation that reads back to the
    same float, so :func:`parse_fis` of this text gives an equal system. The text is
    returned; saving it is the caller's (``Path(name).write_text(fis_text(system))``).

    Parameters
    ----------
    system : SugenoSystem
        The system.

    Returns
    -------
    str
        The ``.fis`` text, lines ending in ``\\n``.

    Examples
    --------
    >>> from firefleet.control.fuzzy import fis_text, parse_fis, read_fis
    >>> from firefleet.control.path_following import builtin_fis_path
    >>> system = read_fis(builtin_fis_path("lambda_correction"))
    >>> text = fis_text(system)
    >>> text.splitlines()[:3]
    ['[System]', "Name='lambda_correction'", "Type='sugeno'"]
    >>> parse_fis(text) == system
    True
    """
    lines = [
        "[System]",
        f"Name='{system.name}'",
        "Type='sugeno'",
        "Version=2.0",
        f"NumInputs={len(system.inputs)}",
        f"NumOutputs={len(system.outputs)}",
        f"NumRules={len(system.rules)}",
        f"AndMethod='{system.and_method}'",
        f"OrMethod='{system.or_method}'",
        "ImpMethod='prod'",
        "AggMethod='sum'",
        f"DefuzzMethod='{system.defuzz}'",
    ]
    variables: list[tuple[str, FuzzyInput | FuzzyOutput]] = [
        *((f"Input{k}", v) for k, v in enumerate(system.inputs, start=1)),
        *((f"Output{k}", v) for k, v in enumerate(system.outputs, start=1)),
    ]
    for section, var in variables:
        mfs: Sequence[MembershipFunction | SugenoOutputMf] = var.mfs
        lines += [
            "",
            f"[{section}]",
            f"Name='{var.name}'",
            f"Range={_nums(var.range)}",
            f"NumMFs={len(var.mfs)}",
        ]
        lines += [
            f"MF{m}='{mf.name}':'{mf.kind}',{_nums(mf.params)}" for m, mf in enumerate(mfs, start=1)
        ]
    lines += ["", "[Rules]"]
    for r in system.rules:
        ante = " ".join(str(a) for a in r.antecedent)
        cons = " ".join(str(c) for c in r.consequent)
        lines.append(f"{ante}, {cons} ({_num(r.weight)}) : {1 if r.connective == 'and' else 2}")
    return "\n".join(lines) + "\n"


def read_fis(path: str | Path) -> SugenoSystem:
    """Read a MATLAB ``.fis`` file (Sugeno type); see :func:`parse_fis`.

    Raises
    ------
    InputError
        Missing or unreadable file, or any error of :func:`parse_fis`.
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{p}: no such file") from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read: {exc.strerror}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")  # MATLAB on Windows writes the system code page
    return parse_fis(text, origin=str(p))


_SECTION_RE = re.compile(r"^\[(System|Input(\d+)|Output(\d+)|Rules)\]$", re.IGNORECASE)
_KEY_RE = re.compile(r"^([A-Za-z][A-Za-z0-9]*)\s*=\s*(.*)$")
_MF_RE = re.compile(r"^'([^']*)'\s*:\s*'([^']*)'\s*,\s*\[([^\]]*)\]$")
_RULE_RE = re.compile(r"^([^,(:]*?)(?:,([^(:]*?))?\s*(?:\(([^)]*)\))?\s*(?::\s*(\S+))?$")
_SYSTEM_KEYS = (
    "Name",
    "Type",
    "Version",
    "NumInputs",
    "NumOutputs",
    "NumRules",
    "AndMethod",
    "OrMethod",
    "ImpMethod",
    "AggMethod",
    "DefuzzMethod",
)


@dataclass
class _Section:
    kind: str  # "System", "Input", "Output", "Rules"
    number: int  # Input/Output number, else 0
    line: int
    entries: list[tuple[int, str]] = field(default_factory=list)  # (line number, text)


class _Parser:
    """One ``.fis`` text: sections, then a validated :class:`SugenoSystem`."""

    def __init__(self, text: str, origin: str) -> None:
        self.origin = origin
        self.sections: list[_Section] = []
        self.n_lines = 0
        for number, raw in enumerate(text.splitlines(), start=1):
            self.n_lines = number
            line = raw.strip()
            if not line or line[0] in "%#":
                continue
            head = _SECTION_RE.match(line)
            if head:
                name = head.group(1).lower()
                kind = "Input" if head.group(2) else "Output" if head.group(3) else name.title()
                num = int(head.group(2) or head.group(3) or 0)
                self.sections.append(_Section(kind, num, number))
            elif line.startswith("["):
                self.fail(number, f"unknown section {line}")
            elif not self.sections:
                self.fail(number, f"text before the first section: {line!r}")
            else:
                self.sections[-1].entries.append((number, line))

    def fail(self, line: int, what: str) -> NoReturn:
        raise InputError(f"{self.origin}:{line}: {what}")

    def keys(self, section: _Section, allowed: tuple[str, ...]) -> dict[str, tuple[int, str]]:
        """key -> (line, value) of a key=value section; MFk keys are returned as given."""
        found: dict[str, tuple[int, str]] = {}
        for line, text in section.entries:
            m = _KEY_RE.match(text)
            if not m:
                self.fail(line, f"expected key=value in [{self.label(section)}], got {text!r}")
            key, value = m.group(1), m.group(2).strip()
            # "MF" in allowed stands for the numbered keys MF1, MF2, ...; bare "MF" is unknown
            canonical = next((k for k in allowed if k != "MF" and k.lower() == key.lower()), None)
            if canonical is None and re.fullmatch(r"MF\d+", key, re.IGNORECASE) and "MF" in allowed:
                canonical = "MF" + str(int(key[2:]))
            if canonical is None:
                self.fail(line, f"unknown key {key!r} in [{self.label(section)}]")
            if canonical in found:
                self.fail(line, f"{canonical} given twice in [{self.label(section)}]")
            found[canonical] = (line, value)
        return found

    @staticmethod
    def label(section: _Section) -> str:
        return f"{section.kind}{section.number}" if section.number else section.kind

    def string(self, line: int, value: str) -> str:
        if len(value) >= 2 and value[0] == value[-1] == "'":
            return value[1:-1]
        if "'" in value:
            self.fail(line, f"unbalanced quotes in {value!r}")
        return value

    def integer(self, line: int, key: str, value: str) -> int:
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not (number.is_integer() and number >= 0):
            self.fail(line, f"{key} must be a whole number >= 0, got {value!r}")
        return int(number)

    def numbers(self, line: int, what: str, text: str) -> list[float]:
        values = []
        for token in text.replace(",", " ").split():
            try:
                v = float(token)
            except ValueError:
                self.fail(line, f"{what}: bad number {token!r}")
            if not math.isfinite(v):
                self.fail(line, f"{what}: {token} is not a finite number")
            values.append(v)
        return values

    def required(
        self, found: dict[str, tuple[int, str]], key: str, section: _Section
    ) -> tuple[int, str]:
        if key not in found:
            self.fail(section.line, f"[{self.label(section)}] has no {key}")
        return found[key]

    def parse(self) -> SugenoSystem:
        systems = [s for s in self.sections if s.kind == "System"]
        if not systems:
            self.fail(1, "missing [System] section")
        if len(systems) > 1:
            self.fail(systems[1].line, "[System] given twice")
        sysec = systems[0]
        sysk = self.keys(sysec, _SYSTEM_KEYS)
        type_line, type_value = self.required(sysk, "Type", sysec)
        fis_type = self.string(type_line, type_value).lower()
        if fis_type == "mamdani":
            self.fail(
                type_line,
                "Type='mamdani': only Sugeno (Takagi-Sugeno) systems can be evaluated; "
                "convert it in MATLAB with convertToSugeno (or mam2sug) first",
            )
        if fis_type != "sugeno":
            self.fail(type_line, f"Type must be 'sugeno', got {type_value}")
        if "Version" in sysk:
            line, value = sysk["Version"]
            if self.string(line, value) not in ("1.0", "2.0", "1", "2"):
                self.fail(line, f"Version {value}: only .fis versions 1.0 and 2.0 are known")
        counts = {}
        for key in ("NumInputs", "NumOutputs", "NumRules"):
            line, value = self.required(sysk, key, sysec)
            counts[key] = (line, self.integer(line, key, value))
        methods = {}
        for key, allowed, default in (
            ("AndMethod", AND_METHODS, "prod"),
            ("OrMethod", OR_METHODS, "probor"),
            ("DefuzzMethod", DEFUZZ_METHODS, "wtaver"),
            ("ImpMethod", ("prod", "min"), "prod"),
            ("AggMethod", ("sum", "max", "probor"), "sum"),
        ):
            if key not in sysk:
                methods[key] = default
                continue
            line, value = sysk[key]
            method = self.string(line, value)
            if method not in allowed:
                self.fail(
                    line, f"{key} {value} is not supported; expected one of {', '.join(allowed)}"
                )
            methods[key] = method
        if methods["ImpMethod"] != "prod" or methods["AggMethod"] != "sum":
            logger.info(
                "%s: ImpMethod=%s, AggMethod=%s play no part in a Sugeno output (MATLAB "
                "ignores them too)",
                self.origin,
                methods["ImpMethod"],
                methods["AggMethod"],
            )
        name_line, name_value = self.required(sysk, "Name", sysec)
        name = self.string(name_line, name_value)

        n_in_line, n_in = counts["NumInputs"]
        n_out_line, n_out = counts["NumOutputs"]
        inputs = [self.variable(s, "Input", n_in) for s in self.numbered("Input", n_in, n_in_line)]
        outputs_secs = self.numbered("Output", n_out, n_out_line)
        outputs = [self.output(s, n_in) for s in outputs_secs]
        rules = self.rules(inputs, outputs, counts["NumRules"])
        try:
            return SugenoSystem(
                name=name,
                inputs=tuple(inputs),
                outputs=tuple(outputs),
                rules=tuple(rules),
                and_method=methods["AndMethod"],  # type: ignore[arg-type]
                or_method=methods["OrMethod"],  # type: ignore[arg-type]
                defuzz=methods["DefuzzMethod"],  # type: ignore[arg-type]
            )
        except InputError as exc:
            self.fail(sysec.line, str(exc))

    def numbered(self, kind: str, count: int, count_line: int) -> list[_Section]:
        secs = [s for s in self.sections if s.kind == kind]
        by_number: dict[int, _Section] = {}
        for s in secs:
            if s.number in by_number:
                self.fail(s.line, f"[{kind}{s.number}] given twice")
            if not 1 <= s.number <= count:
                self.fail(s.line, f"[{kind}{s.number}] but Num{kind}s={count}")
            by_number[s.number] = s
        for k in range(1, count + 1):
            if k not in by_number:
                self.fail(count_line, f"Num{kind}s={count} but there is no [{kind}{k}] section")
        if count == 0:
            self.fail(count_line, f"Num{kind}s must be at least 1")
        return [by_number[k] for k in range(1, count + 1)]

    def mf_entries(
        self, sec: _Section, found: dict[str, tuple[int, str]]
    ) -> list[tuple[int, str, str, list[float]]]:
        line, value = self.required(found, "NumMFs", sec)
        n_mfs = self.integer(line, "NumMFs", value)
        mf_keys = sorted((int(k[2:]), k) for k in found if k.startswith("MF"))
        numbers = {n for n, _ in mf_keys}
        # lazily: NumMFs may be huge (1e308), the first gap is at most len(numbers) + 1
        missing = next((k for k in range(1, n_mfs + 1) if k not in numbers), None)
        extra = sorted(n for n in numbers if not 1 <= n <= n_mfs)
        if missing is not None or extra:
            what = f"missing MF{missing}" if missing else f"MF{extra[0]} beyond NumMFs={n_mfs}"
            where = found[f"MF{extra[0]}"][0] if extra and missing is None else line
            self.fail(where, f"[{self.label(sec)}] NumMFs={n_mfs}: {what}")
        out = []
        for _, key in mf_keys:
            mf_line, text = found[key]
            m = _MF_RE.match(text)
            if not m:
                self.fail(
                    mf_line,
                    f"{key}: expected 'name':'type',[params], got {text!r}",
                )
            params = self.numbers(mf_line, key, m.group(3))
            out.append((mf_line, m.group(1), m.group(2), params))
        return out

    def trim_padding(self, line: int, key: str, params: list[float], n: int) -> list[float]:
        """Old MATLAB files pad parameter rows with zeros to a common width."""
        if len(params) > n and all(p == 0.0 for p in params[n:]):
            return params[:n]
        return params

    def variable(self, sec: _Section, kind: str, n_in: int) -> FuzzyInput:
        found = self.keys(sec, ("Name", "Range", "NumMFs", "MF"))
        name = self.string(*self.required(found, "Name", sec))
        range_ = self.range(sec, found)
        mfs = []
        for k, (line, mf_name, mf_type, params) in enumerate(self.mf_entries(sec, found), 1):
            if mf_type not in N_PARAMS:
                hint = (
                    " (an output type; inputs take trimf, trapmf, ...)"
                    if mf_type
                    in (
                        "constant",
                        "linear",
                    )
                    else ""
                )
                self.fail(
                    line,
                    f"MF{k}: unknown membership function type {mf_type!r}{hint}; "
                    f"expected one of {', '.join(MF_KINDS)}",
                )
            params = self.trim_padding(line, f"MF{k}", params, N_PARAMS[mf_type])
            try:
                mfs.append(MembershipFunction(mf_name, mf_type, tuple(params)))  # type: ignore[arg-type]
            except InputError as exc:
                self.fail(line, f"MF{k}: {exc}")
        try:
            return FuzzyInput(name, range_, tuple(mfs))
        except InputError as exc:
            self.fail(sec.line, str(exc))

    def range(self, sec: _Section, found: dict[str, tuple[int, str]]) -> tuple[float, float]:
        line, value = self.required(found, "Range", sec)
        m = re.fullmatch(r"\[([^\]]*)\]", value)
        if not m:
            self.fail(line, f"Range must be [min max], got {value!r}")
        values = self.numbers(line, "Range", m.group(1))
        if len(values) != 2 or values[0] > values[1]:
            self.fail(line, f"Range must be [min max] with min <= max, got {value}")
        problem = range_problem(values[0], values[1])
        if problem is not None:
            self.fail(line, f"[{self.label(sec)}] Range={value}: {problem}")
        return values[0], values[1]

    def output(self, sec: _Section, n_in: int) -> FuzzyOutput:
        found = self.keys(sec, ("Name", "Range", "NumMFs", "MF"))
        name = self.string(*self.required(found, "Name", sec))
        range_ = self.range(sec, found)
        mfs = []
        for k, (line, mf_name, mf_type, params) in enumerate(self.mf_entries(sec, found), 1):
            if mf_type not in ("constant", "linear"):
                self.fail(
                    line,
                    f"MF{k}: a Sugeno output takes 'constant' or 'linear', got {mf_type!r}",
                )
            n = 1 if mf_type == "constant" else n_in + 1
            params = self.trim_padding(line, f"MF{k}", params, n)
            if len(params) != n:
                self.fail(
                    line,
                    f"MF{k}: {mf_type} takes {n} parameter(s)"
                    + ("" if n == 1 else " (one per input, then the constant)")
                    + f", got {len(params)}",
                )
            try:
                mfs.append(SugenoOutputMf(mf_name, mf_type, tuple(params)))  # type: ignore[arg-type]
            except InputError as exc:
                self.fail(line, f"MF{k}: {exc}")
        try:
            return FuzzyOutput(name, range_, tuple(mfs))
        except InputError as exc:
            self.fail(sec.line, str(exc))

    def rules(
        self, inputs: list[FuzzyInput], outputs: list[FuzzyOutput], count: tuple[int, int]
    ) -> list[Rule]:
        secs = [s for s in self.sections if s.kind == "Rules"]
        count_line, n_rules = count
        if not secs:
            self.fail(count_line, f"NumRules={n_rules} but there is no [Rules] section")
        if len(secs) > 1:
            self.fail(secs[1].line, "[Rules] given twice")
        sec = secs[0]
        if len(sec.entries) != n_rules:
            self.fail(
                count_line,
                f"NumRules={n_rules} but [Rules] (line {sec.line}) has {len(sec.entries)} rule(s)",
            )
        n_in, n_out = len(inputs), len(outputs)
        rules = []
        for k, (line, text) in enumerate(sec.entries, start=1):
            m = _RULE_RE.match(text)
            if not m:
                self.fail(
                    line,
                    f"rule {k}: expected 'in1 .. inN, out1 .. outM (weight) : 1|2', got {text!r}",
                )
            first = self.indices(line, k, m.group(1))
            if m.group(2) is not None:  # with the comma: antecedent, consequent
                ante, cons = first, self.indices(line, k, m.group(2))
                if len(ante) != n_in:
                    self.fail(line, f"rule {k}: {len(ante)} antecedent indices for {n_in} inputs")
                if len(cons) != n_out:
                    self.fail(line, f"rule {k}: {len(cons)} consequent indices for {n_out} outputs")
            else:  # without the comma: the first n_in numbers are the antecedent
                if len(first) != n_in + n_out:
                    self.fail(
                        line,
                        f"rule {k}: {len(first)} indices for {n_in} inputs and {n_out} outputs",
                    )
                ante, cons = first[:n_in], first[n_in:]
            weight = 1.0
            if m.group(3) is not None:
                values = self.numbers(line, f"rule {k} weight", m.group(3))
                if len(values) != 1 or not 0.0 <= values[0] <= 1.0:
                    self.fail(
                        line, f"rule {k}: weight must be one number in [0, 1], got ({m.group(3)})"
                    )
                weight = values[0]
            connective = "and"
            if m.group(4) is not None:
                if m.group(4) not in ("1", "2"):
                    self.fail(
                        line, f"rule {k}: connective must be 1 (AND) or 2 (OR), got {m.group(4)!r}"
                    )
                connective = "and" if m.group(4) == "1" else "or"
            for i, (a, var) in enumerate(zip(ante, inputs, strict=True), start=1):
                if abs(a) > len(var.mfs):
                    self.fail(
                        line,
                        f"rule {k}: input {i} ({var.name!r}) has no membership function {abs(a)} "
                        f"(it has {len(var.mfs)})",
                    )
            for j, (c, out) in enumerate(zip(cons, outputs, strict=True), start=1):
                if c < 0:
                    self.fail(
                        line,
                        f"rule {k}: output {j}: negative (NOT) consequents have no meaning "
                        "in a Sugeno system",
                    )
                if c > len(out.mfs):
                    self.fail(
                        line,
                        f"rule {k}: output {j} ({out.name!r}) has no membership function {c} "
                        f"(it has {len(out.mfs)})",
                    )
            try:
                rules.append(Rule(tuple(ante), tuple(cons), weight, connective))  # type: ignore[arg-type]
            except InputError as exc:
                self.fail(line, f"rule {k}: {exc}")
        return rules

    def indices(self, line: int, k: int, text: str) -> list[int]:
        values = self.numbers(line, f"rule {k}", text)
        for v in values:
            if not v.is_integer():
                self.fail(
                    line, f"rule {k}: index {v:g} is not a whole number (hedges are not supported)"
                )
        return [int(v) for v in values]


def parse_fis(text: str, *, origin: str = "<string>") -> SugenoSystem:
    """Parse MATLAB ``.fis`` text into a :class:`SugenoSystem`.

    Reads what MATLAB's ``writefis`` writes (Version 2.0: quoted values,
    ``Range=[a b]``, ``MF1='name':'trimf',[a b c]``, rule lines
    ``1 0 2 0, 1 3 (1) : 1``) and the older files shipped with the toolbox:
    ``%`` comment lines, spaces around ``=``, no ``Version`` line, parameter rows
    padded with trailing zeros, ``ImpMethod``/``AggMethod`` other than
    ``prod``/``sum`` (they do not affect a Sugeno output), rule lines without the
    comma, the weight or the connective (defaults 1 and AND).

    Parameters
    ----------
    text : str
        The file's text.
    origin : str
        Its name in error messages.

    Returns
    -------
    SugenoSystem

    Raises
    ------
    InputError
        ``"origin:LINE: what"`` for the first problem: a Mamdani system (only Sugeno
        systems are evaluated), a missing section or key, a bad number, a membership
        function index out of range, a wrong parameter count, an unknown
        membership function type or method, counts that disagree with the sections.
    """
    return _Parser(text, origin).parse()
