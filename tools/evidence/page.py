"""The results page: docs/results/index.html from entries.py, the committed figures (found by
glob pattern, so figures added later appear on the next build). Anchors are <a id> elements
(what tools/tests/docs_links.py resolves in links from Markdown) and the quick pass' results.

Committed figures are linked where they lie (a relative path from the page's folder), so
the page shows exactly what the repository holds; what the quick pass drew lies beside
the page. PNGs under tools/*/figures that no entry claims are listed at the end, and the
chapter-4 summary JSON of tools/pssmlt/chapter4.py (ch4_summary*.json) is tabulated when
present."""
import datetime
import glob
import html
import json
import os

from tools.evidence import entries
from tools.tttools import host as tthost

ROOT = tthost.ROOT
OUTCOMES = {"wins": "#2a7d2a", "ties": "#5a6d8a", "loses": "#b03030", "mixed": "#a0702a",
            "not compared": "#777", "not measured yet": "#999"}

CSS = """
body { font: 15px/1.45 system-ui, sans-serif; max-width: 1100px; margin: 2em auto; padding: 0 1em; color: #222 }
h1 { font-size: 1.6em } h2 { margin-top: 2em; border-bottom: 1px solid #ccc }
h3 { margin-top: 1.6em }
table { border-collapse: collapse; margin: .6em 0 } td, th { border: 1px solid #ccc; padding: 3px 7px; vertical-align: top; font-size: 14px }
th { background: #f3f3f3; text-align: left }
.cmp td:first-child { width: 9em; font-weight: 600 }
pre { background: #f6f6f6; padding: .6em; overflow-x: auto; white-space: pre-wrap; font-size: 13px }
.figs img { max-width: 520px; width: 48%; margin: 2px; border: 1px solid #ddd }
.outcome { padding: 1px 7px; border-radius: 4px; color: #fff; font-weight: 600 }
.note { color: #555; font-size: 13px }
"""


def _e(s):
    return html.escape(str(s), quote=True)


def rel(path, out):
    """A link from the page in `out` to `path` (absolute), URL-quoted."""
    from urllib.parse import quote
    return quote(os.path.relpath(path, out).replace(os.sep, "/"))


def committed(patterns):
    """The committed files the glob patterns (relative to ROOT) match, in a stable order."""
    seen, out = set(), []
    for p in patterns:
        for f in sorted(glob.glob(os.path.join(ROOT, p))):
            if f not in seen:
                seen.add(f)
                out.append(f)
    return out


def _figs(files, out, caption):
    if not files:
        return ""
    imgs = "".join(f'<a href="{rel(f, out)}"><img src="{rel(f, out)}" alt="{_e(os.path.basename(f))}" '
                   f'title="{_e(os.path.relpath(f, ROOT))}"></a>' for f in files)
    return f'<p class="note">{caption}</p><div class="figs">{imgs}</div>'


def _table(t):
    if not t:
        return ""
    head = "".join(f"<th>{_e(h)}</th>" for h in t["head"])
    body = "".join("<tr>" + "".join(f"<td>{_e(c)}</td>" for c in r) + "</tr>" for r in t["rows"])
    note = f'<p class="note">{_e(t["note"])}</p>' if t.get("note") else ""
    return f"<table><tr>{head}</tr>{body}</table>{note}"


def ch4_summary_tables():
    """Tables of tools/pssmlt/chapter4.py's summary (ch4_summary*.json) when committed."""
    out = []
    for f in committed(["tools/pssmlt/figures/ch4_summary*.json"]):
        try:
            scenes = json.load(open(f))["scenes"]
        except (OSError, ValueError, KeyError):
            continue
        rows = []
        for name, s in sorted(scenes.items()):
            for e in s.get("equal_mutations", []):
                o, u = e.get("original", {}), e.get("ours", {})
                if "rrmse" in o and "rrmse" in u:
                    rd = e.get("rel_diff_median")
                    rows.append([name, e.get("mpp"), f"{o['rrmse']:.4g}", f"{u['rrmse']:.4g}",
                                 "-" if rd is None else f"{rd:+.1%}", e.get("reps", "")])
        if rows:
            out.append((f, {"head": ["scene", "mutations/px", "original rRMSE", "ours rRMSE",
                                     "ours against original (median over repetitions)",
                                     "repetitions"], "rows": rows}))
    return out


def _measured(en, files, regen):
    """An entry is measured when it has a figure, or numbers unless it needs a figure."""
    return bool(files or regen or (en["ours"] and not en.get("needs_figure")))


def build(out, quick_results, mode):
    """Writes out/index.html; returns its path."""
    claimed = set()
    by_ch = {}
    for en in entries.E:
        by_ch.setdefault(en["chapter"], []).append(en)
    parts = [f"<!doctype html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>tunetrace results"
             f"</title><style>{CSS}</style></head><body>",
             "<h1>tunetrace: results beside the thesis</h1>",
             "<p>Per thesis chapter: the thesis' figure, ours, our numbers beside the thesis' with "
             "the settings of each, the command that measured ours, and the outcome. Numbers are "
             "quoted from the README named under each entry (the measurement's full report) or "
             "read from the committed JSON; committed figures were measured at the full settings "
             "of the command shown. The <em>quick pass</em> (<code>/usr/bin/python3 -m "
             "tools.evidence.run --quick</code>, part of the test suite) re-runs every figure tool "
             "at toy sizes so that a tool that stops working fails the suite, and redraws the "
             "figures that come from committed data. Re-measuring everything takes hours: "
             "<code>/usr/bin/python3 -m tools.evidence.run --full</code> lists the commands (<a href=\"full_commands.txt\">"
             "full_commands.txt</a>).</p>",
             f"<p class=\"note\">Built {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC "
             f"by the {mode} pass.</p>"]
    # outcome table (also what README.md summarises)
    parts.append('<h2><a id="outcomes"></a>Outcomes at a glance</h2><table><tr><th>chapter</th><th>thesis</th>'
                 '<th>what</th><th>outcome</th></tr>')
    for ch in (3, 4, 5, 0):
        for en in by_ch.get(ch, []):
            oc = en["outcome"] if _measured(en, committed(en["figures"]), en["regenerated"]) \
                else "not measured yet"
            parts.append(f'<tr><td>{ch or "-"}</td><td>{_e(en["thesis"])}</td><td><a href="#{en["id"]}">'
                         f'{_e(en["title"])}</a></td><td><span class="outcome" style="background:'
                         f'{OUTCOMES[oc]}">{_e(oc)}</span></td></tr>')
    parts.append("</table>")
    for ch in (3, 4, 5, 0):
        parts.append(f'<h2><a id="ch{ch}"></a>{_e(entries.CHAPTERS[ch])}</h2>')
        for en in by_ch.get(ch, []):
            files = committed(en["figures"])
            claimed.update(files)
            regen = [os.path.join(out, r) for r in en["regenerated"]
                     if os.path.exists(os.path.join(out, r))]
            quick = [os.path.join(out, q) for q in en["quick"] if os.path.exists(os.path.join(out, q))]
            measured = _measured(en, files, regen)
            oc = en["outcome"] if measured else "not measured yet"
            parts.append(f'<h3><a id="{en["id"]}"></a>{_e(en["thesis"])}: {_e(en["title"])}</h3>')
            if not measured:
                parts.append("<p><strong>Not measured yet.</strong></p>")
            parts.append(_figs(regen, out, "Redrawn by the quick pass from committed data:"))
            parts.append(_figs(files, out, "Committed figures (full settings):"))
            if callable(en["table"]):
                parts.append(_table(en["table"]()))
            if en["id"] == "ch4-fig46":
                for f, t in ch4_summary_tables():
                    parts.append(f'<p class="note">From <a href="{rel(f, out)}">'
                                 f'{_e(os.path.relpath(f, ROOT))}</a>:</p>' + _table(t))
            rows = [("ours", en["ours"]), ("our settings", en["ours_settings"]),
                    ("thesis", en["thesis_numbers"]), ("thesis settings", en["thesis_settings"])]
            parts.append('<table class="cmp">' + "".join(
                f"<tr><td>{k}</td><td>{_e(v) if v else 'not measured yet'}</td></tr>" for k, v in rows)
                + "</table>")
            parts.append(f"<p>Command (full settings):</p><pre>{_e(en['command'])}</pre>")
            parts.append(f'<p>Outcome: <span class="outcome" style="background:{OUTCOMES[oc]}">'
                         f'{_e(oc)}</span> {_e(en["why"])}</p>')
            srcs = ", ".join(f'<a href="{rel(os.path.join(ROOT, s), out)}">{_e(s)}</a>' for s in en["source"])
            parts.append(f'<p class="note">Source: {srcs}</p>')
            parts.append(_figs(quick, out, "Quick pass (the same tool at toy sizes: shows it runs, "
                                           "not a result):"))
    # every committed figure no entry claims, so new figures are visible at once
    rest = [f for f in committed(["tools/*/figures/*.png", "tools/*/figures/*/*.png"])
            if f not in claimed]
    parts.append('<h2><a id="other"></a>Other committed figures</h2>')
    if rest:
        parts.append("<ul>" + "".join(f'<li><a href="{rel(f, out)}">{_e(os.path.relpath(f, ROOT))}</a></li>'
                                      for f in rest) + "</ul>")
    else:
        parts.append("<p>None.</p>")
    # the quick pass itself
    parts.append('<h2><a id="quick-pass"></a>The quick pass</h2><table><tr><th>step</th><th>result</th>'
                 '<th>seconds</th><th>outputs</th></tr>')
    for name, r in quick_results.items():
        outs = ", ".join(f'<a href="{rel(os.path.join(out, p), out)}">{_e(p)}</a>' for p in r["pngs"])
        parts.append(f"<tr><td>{_e(name)}</td><td>{'ok' if r['ok'] else 'FAILED: ' + _e(r['error'][:300])}"
                     f"</td><td>{r['seconds']}</td><td>{outs}</td></tr>")
    parts.append("</table></body></html>\n")
    path = os.path.join(out, "index.html")
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(p for p in parts if p))
    os.replace(tmp, path)
    return path
