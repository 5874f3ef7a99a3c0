"""The reproduction report: one HTML page comparing each experiment with the deliverable.

The page follows the deliverable's own order: its sections 2.3 to 2.7, each with the
experiments that reproduce its figures, and then, apart, what firefleet adds beyond the
deliverable (an entry whose ``reproduces`` starts with "beyond"). A figure shared by
several experiments (the fuzzy controller of every path-following run) is shown once,
in the first entry that has it; the later ones link to it.
"""

from __future__ import annotations

import datetime as dt
import html
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

__all__ = ["SECTIONS", "ReportEntry", "ReportRun", "format_value", "render_index", "section_of"]


@dataclass(frozen=True)
class ReportEntry:
    """One experiment of the report.

    Attributes
    ----------
    name, title, reproduces, deliverable_says : str
        From the scenario. ``reproduces`` names the deliverable's figures
        ("Figures 32-35") or section ("Section 2.7.1"), or starts with "beyond" for
        what the deliverable does not have.
    folder : str
        The run's folder, relative to the report's ``index.html``.
    figures : tuple of str
        Figure file names inside ``folder``.
    document : dict
        The run's ``metrics.json`` (or ``summary.json``) object: ``claims`` and metrics.
    command : str
        The command line that makes this run again (default ``firefleet run NAME``).
    links : tuple of str
        Files inside ``folder`` the entry links to (the run's data).
    captions : mapping of str to str
        A caption for some of the figures, by file name.
    pass_rates : mapping of str to (int, int)
        Claim name and bound (``"rise_time_s < 0.2"``, as
        :func:`firefleet.sweep.claim_key`) -> (runs in which it holds, runs) over seeds
        (``firefleet reproduce --seeds``); empty for seed 0 alone.
    seeds : str
        The seeds of ``pass_rates`` as typed (``"0:20"``).
    """

    name: str
    title: str
    reproduces: str
    deliverable_says: str
    folder: str
    figures: tuple[str, ...]
    document: dict[str, Any]
    command: str = ""
    links: tuple[str, ...] = ("metrics.json", "result.npz")
    captions: Mapping[str, str] = field(default_factory=dict)
    pass_rates: Mapping[str, tuple[int, int]] = field(default_factory=dict)
    seeds: str = ""


@dataclass(frozen=True)
class ReportRun:
    """One entry of the report that is not a scenario run.

    Attributes
    ----------
    name : str
        Folder name and anchor.
    title, reproduces, deliverable_says : str
        As a scenario's.
    command : str
        The command line that reproduces the numbers outside the report.
    files : mapping of str to bytes
        Figures (PNG) and data by file name, for the caller to write into ``name/``.
    figures : tuple of str
        The files that are figures, in the order the report shows them.
    document : dict
        ``{"scenario": name, "claims": [...], **metrics}``, written as ``metrics.json``.
    captions : mapping of str to str
        A caption for some of the figures, by file name.
    """

    name: str
    title: str
    reproduces: str
    deliverable_says: str
    command: str
    files: Mapping[str, bytes]
    figures: tuple[str, ...]
    document: dict[str, Any] = field(default_factory=dict)
    captions: Mapping[str, str] = field(default_factory=dict)


SECTIONS: tuple[tuple[str, str, tuple[int, int]], ...] = (
    ("2.3", "Formation control about a virtual leader", (4, 6)),
    ("2.6.4.1", "DC motor and wheel-speed PID", (24, 25)),
    ("2.6.4.2", "Fuzzy path following, one robot", (26, 31)),
    ("2.6.5", "Cooperative path following", (32, 37)),
    ("2.7", "Image processing and SLAM", (38, 46)),
)
"""The deliverable's sections in the report: number, title, range of its figure numbers."""

SHARED_FIGURES = {
    "controller.png": "the fuzzy path-following controller (the same in every path-following run)"
}
"""Figures that several runs make alike: shown once, where they first appear."""

_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 1000px; margin: 2em auto; color: #222;
       padding: 0 1em; line-height: 1.45; }
h1 { margin-bottom: 0.2em; }
h2.part { margin-top: 2.5em; border-bottom: 3px solid #444; }
section { border-top: 1px solid #ccc; margin-top: 2em; padding-top: 0.5em; }
.scroll { overflow-x: auto; max-width: 100%; }
table { border-collapse: collapse; margin: 0.8em 0; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.7em; text-align: left; vertical-align: top; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.nw { white-space: nowrap; }
td.src { min-width: 12em; }
.pass { color: #11772d; font-weight: 600; } .fail { color: #b3141b; font-weight: 600; }
blockquote { color: #555; border-left: 3px solid #ccc; margin: 0.5em 0; padding-left: 1em; }
img { max-width: 100%; height: auto; border: 1px solid #eee; }
.small { color: #666; font-size: 0.9em; }
code { overflow-wrap: anywhere; }
"""

_NOT_DEFINED = (
    "n/a: the quantity is not defined for this run (a spread or a margin over a single "
    "robot, or an event that never happened)"
)


def section_of(reproduces: str) -> str | None:
    """The deliverable section an entry belongs to, from its ``reproduces`` text.

    Parameters
    ----------
    reproduces : str
        ``"Figures 32-35"``, ``"Section 2.7.2"``, ``"beyond Figure 4: ..."``.

    Returns
    -------
    str or None
        The section number of :data:`SECTIONS`, or None for an entry beyond the
        deliverable (or one that names no figure or section).

    Examples
    --------
    >>> section_of("Figures 32-35"), section_of("Section 2.7.1: thermal imaging")
    ('2.6.5', '2.7')
    >>> section_of("beyond Figure 4: regular polygon") is None
    True
    """
    text = reproduces.strip()
    if text.lower().startswith("beyond"):
        return None
    named = re.match(r"section\s+(\d+(?:\.\d+)*)", text, flags=re.IGNORECASE)
    if named:
        number = named.group(1)
        for key, _, _ in SECTIONS:
            if number == key or number.startswith(key + "."):
                return key
        return None
    figure = re.search(r"(\d+)", text)
    if figure is None:
        return None
    n = int(figure.group(1))
    for key, _, (first, last) in SECTIONS:
        if first <= n <= last:
            return key
    return None


def format_value(value: Any) -> str:
    """A measured value as the report shows it: enough digits, no list of one.

    Examples
    --------
    >>> format_value(18.737199999999987), format_value([3.6]), format_value(4.6513e-06)
    ('18.7372', '3.6', '4.6513e-6')
    >>> format_value(float("nan")), format_value([0.5, 0.25])
    ('n/a', '0.5, 0.25')
    """
    if value is None:
        return "n/a"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float | int):
        number = float(value)
        if math.isnan(number):
            return "n/a"
        text = f"{number:.6g}"
        mantissa, _, exponent = text.partition("e")
        return mantissa if not exponent else f"{mantissa}e{int(exponent)}"
    if isinstance(value, Sequence) and not isinstance(value, str):
        items = list(value)
        return format_value(items[0]) if len(items) == 1 else ", ".join(map(format_value, items))
    return str(value)


def _cell(value: Any) -> str:
    """A value as an HTML table cell: a list wraps between its numbers, never inside one."""
    if isinstance(value, list) and len(value) > 1:
        return ", ".join(f"<span class=nw>{html.escape(format_value(v))}</span>" for v in value)
    return f"<span class=nw>{html.escape(format_value(value))}</span>"


def _rate_cell(rate: tuple[int, int] | None) -> str:
    """A claim's pass rate over seeds: ``passed / runs`` and the percentage."""
    if rate is None or rate[1] == 0:
        return "<td class=num>n/a</td>"
    passed, runs = rate
    kind = "pass" if passed == runs else "fail"
    return f"<td class='num {kind}'>{passed}/{runs} ({100 * passed / runs:.0f} %)</td>"


def _has_undefined(value: Any) -> bool:
    if isinstance(value, float):
        return math.isnan(value)
    if isinstance(value, list):
        return any(_has_undefined(v) for v in value)
    return value is None


def _section(entry: ReportEntry, shown_at: dict[str, str]) -> str:
    esc = html.escape
    doc = entry.document
    claims = doc.get("claims", [])
    rows = "".join(
        "<tr><td>{}</td><td class=num>{}</td><td class=num>{}</td>"
        "<td class={}>{}</td>{}<td class=src>{}</td></tr>".format(
            esc(c["name"]),
            esc(str(c["expected"])),
            _cell(c["measured"]),
            "pass" if c["passed"] else "fail",
            "passed" if c["passed"] else "FAILED",
            _rate_cell(entry.pass_rates.get(f"{c['name']} {c['expected']}"))
            if entry.pass_rates
            else "",
            esc(c.get("source", "")),
        )
        for c in claims
    )
    metrics = {k: v for k, v in doc.items() if k not in ("scenario", "claims", "provenance")}
    metric_rows = "".join(
        f"<tr><td>{esc(k)}</td><td class=num>{_cell(v)}</td></tr>"
        for k, v in metrics.items()
        if not isinstance(v, dict)
    )
    undefined = any(_has_undefined(c["measured"]) for c in claims) or any(
        _has_undefined(v) for v in metrics.values()
    )
    note = f"<p class=small>{esc(_NOT_DEFINED)}.</p>" if undefined else ""
    figs = []
    for f in entry.figures:
        if f in SHARED_FIGURES and f in shown_at and shown_at[f] != entry.name:
            figs.append(
                f"<p class=small>{esc(f)}: {esc(SHARED_FIGURES[f])}, shown in "
                f'<a href="#{esc(shown_at[f])}">{esc(shown_at[f])}</a>.</p>'
            )
            continue
        shown_at.setdefault(f, entry.name)
        caption = entry.captions.get(f)
        figs.append(
            f'<p><img src="{esc(entry.folder)}/{esc(f)}" alt="{esc(entry.name)} {esc(f)}">'
            + (f"<br><span class=small>{esc(caption)}</span>" if caption else "")
            + "</p>"
        )
    command = entry.command or f"firefleet run {entry.name}"
    links = "".join(
        f' &middot; <a href="{esc(entry.folder)}/{name}">{name}</a>'
        for name in map(esc, entry.links)
    )
    rate_head = f"<th>holds over seeds {esc(entry.seeds)}</th>" if entry.pass_rates else ""
    claims_table = (
        "<div class=scroll><table><tr><th>claim</th><th>expected</th><th>measured</th>"
        f"<th>result</th>{rate_head}<th>where the bound comes from</th></tr>{rows}</table></div>"
        if claims
        else ""
    )
    return f"""
<section id="{esc(entry.name)}">
<h3>{esc(entry.reproduces)}: {esc(entry.title)}</h3>
<p class=small>run again with <code>{esc(command)}</code>{links}</p>
<p>The deliverable says:</p>
<blockquote>{esc(entry.deliverable_says)}</blockquote>
{"".join(figs)}
{claims_table}{note}
<details><summary>all metrics</summary><div class=scroll><table>{metric_rows}</table></div>
</details>
</section>"""


def _number(entry: ReportEntry) -> float:
    """The first figure or section number an entry names, to sort by."""
    found = re.search(r"\d+(?:\.\d+)?", entry.reproduces)
    return float(found.group(0)) if found else math.inf


def _order(entries: Sequence[ReportEntry]) -> list[tuple[str, str, list[ReportEntry]]]:
    """Entries grouped as the page shows them: the deliverable's sections, then beyond,
    each by the first figure number it names."""
    entries = sorted(entries, key=_number)
    parts: list[tuple[str, str, list[ReportEntry]]] = []
    for key, title, _ in SECTIONS:
        inside = [e for e in entries if section_of(e.reproduces) == key]
        if inside:
            parts.append((key, title, inside))
    beyond = [e for e in entries if section_of(e.reproduces) is None]
    if beyond:
        parts.append(("", "Beyond the deliverable", beyond))
    return parts


def render_index(
    entries: Sequence[ReportEntry], *, version: str, footer: str = "", missing: str = ""
) -> str:
    """The report's ``index.html``.

    Parameters
    ----------
    entries : sequence of ReportEntry
        In the order they were run; the page regroups them by the deliverable's
        sections (:data:`SECTIONS`), then puts what goes beyond the deliverable.
    version : str
        firefleet's version.
    footer : str
        More provenance for the footer (commit, command line), plain text.
    missing : str
        Plain text saying what could not be run (data absent), shown under the summary.
    """
    esc = html.escape
    total = sum(len(e.document.get("claims", [])) for e in entries)
    passed = sum(bool(c["passed"]) for e in entries for c in e.document.get("claims", []))
    verdict = "pass" if passed == total else "fail"
    parts = _order(entries)
    toc = "".join(
        f"<li>{esc(key + ' ' if key else '')}{esc(title)}<ul>"
        + "".join(
            f'<li><a href="#{esc(e.name)}">{esc(e.reproduces)}</a>: {esc(e.title)}</li>'
            for e in inside
        )
        + "</ul></li>"
        for key, title, inside in parts
    )
    shown_at: dict[str, str] = {}
    body = "".join(
        f"<h2 class=part>{esc(key + ' ' if key else '')}{esc(title)}</h2>"
        + "".join(_section(e, shown_at) for e in inside)
        for key, title, inside in parts
    )
    stamp = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    missing_html = f"<p class=small>{esc(missing)}</p>" if missing else ""
    more = f" {esc(footer)}" if footer else ""
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>firefleet reproduction report</title><style>{_STYLE}</style></head>
<body>
<h1>firefleet reproduction report</h1>
<p>Every experiment of the deliverable <em>Design and development of Intelligent Mobile
Robots (IMRs) for disaster mitigation and firefighting</em> that firefleet reproduces,
in the deliverable's order, with our figure and each claim checked against our run;
then what firefleet adds beyond it.</p>
<p class="{verdict}">{passed} of {total} claims passed.</p>
{missing_html}
<ul>{toc}</ul>
{body}
<p class=small>firefleet {esc(version)}, {stamp}.{more}</p>
</body></html>
"""
