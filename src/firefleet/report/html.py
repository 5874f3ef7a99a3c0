"""The reproduction report: one HTML page comparing each experiment with the deliverable."""

from __future__ import annotations

import datetime as dt
import html
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = ["ReportEntry", "render_index"]


@dataclass(frozen=True)
class ReportEntry:
    """One experiment of the report.

    Attributes
    ----------
    name, title, reproduces, deliverable_says : str
        From the scenario.
    folder : str
        The run's folder, relative to the report's ``index.html``.
    figures : tuple of str
        Figure file names inside ``folder``.
    document : dict
        The run's ``metrics.json`` object.
    """

    name: str
    title: str
    reproduces: str
    deliverable_says: str
    folder: str
    figures: tuple[str, ...]
    document: dict[str, Any]


_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 1000px; margin: 2em auto; color: #222;
       padding: 0 1em; line-height: 1.45; }
h1 { margin-bottom: 0.2em; }
section { border-top: 1px solid #ccc; margin-top: 2em; padding-top: 0.5em; }
table { border-collapse: collapse; margin: 0.8em 0; }
th, td { border: 1px solid #ccc; padding: 0.3em 0.7em; text-align: left; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.pass { color: #11772d; font-weight: 600; } .fail { color: #b3141b; font-weight: 600; }
blockquote { color: #555; border-left: 3px solid #ccc; margin: 0.5em 0; padding-left: 1em; }
img { max-width: 100%; border: 1px solid #eee; }
.small { color: #666; font-size: 0.9em; }
"""


def _fmt(value: Any) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        return f"{value:.5g}"
    if isinstance(value, list):
        return "[" + ", ".join(_fmt(v) for v in value) + "]"
    return html.escape(str(value))


def _section(entry: ReportEntry) -> str:
    esc = html.escape
    doc = entry.document
    claims = doc.get("claims", [])
    rows = "".join(
        "<tr><td>{}</td><td>{}</td><td class=num>{}</td>"
        "<td class={}>{}</td><td>{}</td></tr>".format(
            esc(c["name"]),
            esc(c["expected"]),
            _fmt(c["measured"]),
            "pass" if c["passed"] else "fail",
            "passed" if c["passed"] else "FAILED",
            esc(c.get("source", "")),
        )
        for c in claims
    )
    metric_rows = "".join(
        f"<tr><td>{esc(k)}</td><td class=num>{_fmt(v)}</td></tr>"
        for k, v in doc.items()
        if k not in ("scenario", "claims")
    )
    figs = "".join(
        f'<p><img src="{esc(entry.folder)}/{esc(f)}" alt="{esc(entry.name)} {esc(f)}"></p>'
        for f in entry.figures
    )
    return f"""
<section id="{esc(entry.name)}">
<h2>{esc(entry.reproduces)}: {esc(entry.title)}</h2>
<p class=small>scenario <code>{esc(entry.name)}</code> &middot;
run again with <code>firefleet run {esc(entry.name)}</code> &middot;
<a href="{esc(entry.folder)}/metrics.json">metrics.json</a> &middot;
<a href="{esc(entry.folder)}/result.npz">result.npz</a></p>
<p>The deliverable says:</p>
<blockquote>{esc(entry.deliverable_says)}</blockquote>
{figs}
<table><tr><th>claim</th><th>expected</th><th>measured</th><th>result</th><th>source</th></tr>
{rows}</table>
<details><summary>all metrics</summary><table>{metric_rows}</table></details>
</section>"""


def _footer(
    version: str, stamp: str, provenance: Mapping[str, Any], seeds: Mapping[str, int]
) -> str:
    esc = html.escape
    parts = [f"firefleet {esc(version)}"]
    if provenance.get("git_commit"):
        parts.append(f"commit <code>{esc(str(provenance['git_commit']))}</code>")
    parts.append(stamp)
    lines = [", ".join(parts) + "."]
    if provenance.get("command"):
        lines.append(f"Made by <code>{esc(str(provenance['command']))}</code>.")
    if seeds:
        shown = ", ".join(f"{esc(name)} {seed}" for name, seed in seeds.items())
        lines.append(f"Seeds: {shown}.")
    return "<footer><p class=small>" + "<br>".join(lines) + "</p></footer>"


def render_index(
    entries: list[ReportEntry],
    *,
    version: str,
    provenance: Mapping[str, Any] | None = None,
    seeds: Mapping[str, int] | None = None,
) -> str:
    """The report's ``index.html``.

    Parameters
    ----------
    entries : list of ReportEntry
        The experiments, in the report's order.
    version : str
        firefleet's version, named in the footer.
    provenance : mapping, optional
        What made the report (``git_commit``, ``command``, as
        :func:`firefleet.outputs.run_record` gives), named in the footer.
    seeds : mapping of str to int, optional
        Each experiment's random seed, by scenario name, named in the footer.
    """
    total = sum(len(e.document.get("claims", [])) for e in entries)
    passed = sum(c["passed"] for e in entries for c in e.document.get("claims", []))
    verdict = "pass" if passed == total else "fail"
    toc = "".join(
        f'<li><a href="#{html.escape(e.name)}">{html.escape(e.reproduces)}</a>: '
        f"{html.escape(e.title)}</li>"
        for e in entries
    )
    stamp = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    body = "".join(_section(e) for e in entries)
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<title>firefleet reproduction report</title><style>{_STYLE}</style></head>
<body>
<h1>firefleet reproduction report</h1>
<p>Every experiment of the deliverable <em>Design and development of Intelligent Mobile
Robots (IMRs) for disaster mitigation and firefighting</em> that firefleet reproduces,
with our figure and each claim checked against our run.</p>
<p class="{verdict}">{passed} of {total} claims passed.</p>
<ul>{toc}</ul>
{body}
{_footer(version, stamp, provenance or {}, seeds or {})}
</body></html>
"""
