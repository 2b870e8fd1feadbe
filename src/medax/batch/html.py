"""The run's report and a report per part, each one self-contained HTML file (no network):
a sortable table of the parts, the kept-blend reasons grouped over the run, each part's
pictures inlined, and the interactive 3D view of the parts (:mod:`medax.viz.webview`).

Pictures are the PNG views the steps wrote (``medax batch --pictures``), embedded as
``data:`` URIs; the 3D view draws the ``view3d`` data classify and simplify wrote
(``classify.view.json``, ``simplify.view.json``); the sorting is a few lines of inline
JavaScript. The run's report embeds the 3D data of the parts up to :data:`MAX_VIEW_BYTES`
in all; each part's own report (``OUTDIR/<part>/report.html``) always has its own.
"""

from __future__ import annotations

import base64
import html
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

REPORT = "report.html"
#: table columns: heading, record counts key (None: computed)
COLUMNS = (
    ("part", None),
    ("status", None),
    ("faces", "faces"),
    ("fillets", "fillets"),
    ("corner blends", "corner_blends"),
    ("faces after", "faces_after"),
    ("blends found", "blends_found"),
    ("removed", "blends_removed"),
    ("kept", "blends_kept"),
    ("quads", "mesh_quads"),
    ("time s", None),
)
PICTURES = (("classify_png", "classes"), ("simplify_png", "before / after"), ("mesh_png", "mesh"))
#: the 3D views: output key, label
VIEWS = (("classify_view", "classified"), ("simplify_view", "simplified"))
#: the most 3D data (bytes of view JSON) the run's report embeds; parts beyond it are seen
#: in their own reports
MAX_VIEW_BYTES = 20_000_000

_STYLE = """
body{font:14px system-ui,sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse}th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}
th{background:#eee;cursor:pointer;user-select:none}td:first-child,td:nth-child(2){text-align:left}
tr.ok td:nth-child(2){color:#060}tr.refused td:nth-child(2){color:#a60}
tr.failed td:nth-child(2),tr.timeout td:nth-child(2){color:#b00;font-weight:bold}
section{margin:1.5em 0;border-top:1px solid #ccc}img{max-width:32%;margin:4px;border:1px solid #ddd}
svg.hist{margin:4px;border:1px solid #ddd;vertical-align:top}
code{background:#f4f4f4;padding:1px 3px}
"""
_SORT = """
document.querySelectorAll('th').forEach((th,i)=>th.addEventListener('click',()=>{
 const tb=th.closest('table').tBodies[0],rows=[...tb.rows],up=th.dataset.up!=='1';
 th.dataset.up=up?'1':'0';
 const key=r=>{const t=r.cells[i].dataset.v??r.cells[i].textContent,n=parseFloat(t);
  return isNaN(n)?t:n};
 rows.sort((a,b)=>{const x=key(a),y=key(b);return (x>y?1:x<y?-1:0)*(up?1:-1)});
 rows.forEach(r=>tb.appendChild(r))}));
"""


def report_html(
    records: Sequence[Mapping[str, Any]], summary: Mapping[str, Any], outdir: str | Path
) -> str:
    """The run's report text; pictures and 3D data are read from ``outdir``."""
    from medax.viz.webview import page, viewer_html

    e = html.escape
    out = Path(outdir)
    st = summary["status"]
    head = (
        f"{summary['parts']} parts ({summary['skipped']} finished before): ok {st['ok']}, "
        f"refused {st['refused']}, failed {st['failed']}, timeout {st['timeout']}; "
        f"wall {summary['wall_s']:.1f} s, {summary['parts_per_min']:.1f} parts/min"
    )
    rows = []
    for r in records:
        c = r.get("counts", {})
        cells = [
            f'<td><a href="#{e(r["part_dir"])}">{e(r["part_dir"])}</a></td>',
            f"<td>{e(r['status'])}</td>",
        ]
        for _, key in COLUMNS[2:-1]:
            value = c.get(key) if key else None
            cells.append(f"<td>{'' if value is None else int(value)}</td>")
        cells.append(f"<td>{float(r.get('time_s', 0.0)):.1f}</td>")
        rows.append(f'<tr class="{e(r["status"])}">{"".join(cells)}</tr>')
    reasons = "".join(
        f"<tr><td>{e(k)}</td><td>{int(v)}</td></tr>" for k, v in summary["kept_reasons"].items()
    )
    models: list[tuple[str, Mapping[str, Any]]] = []
    first: dict[str, int] = {}
    budget = MAX_VIEW_BYTES
    for r in records:
        files = [out / r["outputs"][k] for k, _ in VIEWS if k in r.get("outputs", {})]
        if sum(p.stat().st_size for p in files if p.is_file()) > budget:
            continue  # not read: seen in the part's own report
        views = _views(r, out)
        size = sum(n for _, _, n in views)
        if views and size <= budget:
            budget -= size
            first[r["part_dir"]] = len(models)
            models.extend((f"{r['part_dir']}: {label}", m) for label, m, _ in views)
    parts = [_part_section(r, out, view=first.get(r["part_dir"])) for r in records]
    heading = "".join(f"<th>{e(h)}</th>" for h, _ in COLUMNS)
    body = (
        f"<h1>medax batch</h1><p>{e(head)}</p>"
        f"<table><thead><tr>{heading}</tr></thead><tbody>{''.join(rows)}</tbody></table>"
        "<h2>Kept blends, by reason</h2>"
        + (
            f"<table><thead><tr><th>reason</th><th>blends</th></tr></thead>"
            f"<tbody>{reasons}</tbody></table>"
            if reasons
            else "<p>none</p>"
        )
        + ("<h2>3D view</h2>" + viewer_html(models) if models else "")
        + "<h2>Parts</h2>"
        + "".join(parts)
        + f"<script>{_SORT}</script>"
    )
    return page(f"medax batch: {outdir}", body, _STYLE)


def part_report_html(r: Mapping[str, Any], outdir: str | Path) -> str:
    """The report of one part (``OUTDIR/<part>/report.html``): its section of the run's
    report with the 3D view of the part first; links are relative to the part's folder."""
    from medax.viz.webview import page, viewer_html

    out = Path(outdir)
    views = [(label, m) for label, m, _ in _views(r, out)]
    body = (
        f"<h1>medax: {html.escape(r['part_dir'])}</h1>"
        + viewer_html(views)
        + _part_section(r, out, prefix="../", heading=False)
        + '<p><a href="../report.html">the run\'s report</a></p>'
    )
    return page(f"medax: {r['part_dir']}", body, _STYLE)


def _views(r: Mapping[str, Any], outdir: Path) -> list[tuple[str, dict[str, Any], int]]:
    """The part's 3D view data that exist: (label, data, bytes)."""
    out = []
    for key, label in VIEWS:
        rel = r.get("outputs", {}).get(key)
        if rel is None or not (outdir / rel).is_file():
            continue
        text = (outdir / rel).read_text(encoding="utf-8")
        try:
            data = json.loads(text)
        except ValueError:
            continue  # a file this run cannot read is left out of the view, not fatal
        out.append((label, data, len(text)))
    return out


def write_report(
    records: Sequence[Mapping[str, Any]], summary: Mapping[str, Any], outdir: str | Path
) -> Path:
    """Write ``outdir/report.html`` and each part's ``outdir/<part>/report.html``, each
    atomically."""
    from medax.io_utils import atomic_path

    text = report_html(records, summary, outdir)
    path = Path(outdir) / REPORT
    for r in records:
        folder = Path(outdir) / r["part_dir"]
        if folder.is_dir():
            with atomic_path(folder / REPORT, "report") as tmp:
                tmp.write_text(part_report_html(r, outdir), encoding="utf-8")
    with atomic_path(path, "report") as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def _part_section(
    r: Mapping[str, Any],
    outdir: Path,
    prefix: str = "",
    view: int | None = None,
    heading: bool = True,
) -> str:
    """A part's section: ``prefix`` before its links (relative to ``outdir``); ``view``: the
    index of its first model in the run's 3D view (a link shows it there)."""
    e = html.escape
    lines = [f"<code>{e(str(r['input']))}</code>", f"status {e(r['status'])}"]
    if r.get("error"):
        lines.append(e(str(r["error"])))
    steps = ", ".join(
        f"{e(k)} {e(v['status'])} {float(v['time_s']):.1f} s" for k, v in r["steps"].items()
    )
    if steps:
        lines.append(steps)
    if r.get("kept_reasons"):
        lines.append("kept: " + ", ".join(f"{e(k)} {int(v)}" for k, v in r["kept_reasons"].items()))
    outputs = r.get("outputs", {})
    imgs = []
    for key, alt in PICTURES:
        if key in outputs and (outdir / outputs[key]).is_file():
            data = base64.b64encode((outdir / outputs[key]).read_bytes()).decode("ascii")
            imgs.append(f'<img alt="{e(alt)}" title="{e(alt)}" src="data:image/png;base64,{data}">')
    imgs.extend(_histograms(outputs, outdir))
    files = [*outputs.values(), f"{r['part_dir']}/batch.log"]
    links = [f'<a href="{e(prefix + p)}">{e(Path(p).name)}</a>' for p in files]
    if heading:
        links.insert(0, f'<a href="{e(r["part_dir"])}/{REPORT}">its report</a>')
    if view is not None:
        show = f"document.getElementById('view').medaxShow({int(view)});return false"
        links.insert(0, f'<a href="#view" onclick="{e(show)}">3D view</a>')
    title = f"<h3>{e(r['part_dir'])}</h3>" if heading else ""
    return (
        f'<section id="{e(r["part_dir"])}">{title}'
        f"<p>{'<br>'.join(lines)}</p><p>{' '.join(links)}</p>{''.join(imgs)}</section>"
    )


#: histogram titles per metric of the mesh report
HISTOGRAMS = {
    "scaled_jacobian": "scaled Jacobian",
    "min_angle": "smallest angle (deg)",
    "max_angle": "largest angle (deg)",
}


def _histograms(outputs: Mapping[str, str], outdir: Path) -> list[str]:
    """Inline SVG bar charts of the mesh report's quality histograms (summed over its
    solids); none when there is no mesh report or it has no histograms."""
    rel = outputs.get("mesh_report")
    if rel is None or not (outdir / rel).is_file():
        return []
    try:
        rep = json.loads((outdir / rel).read_text(encoding="utf-8"))
    except ValueError:
        return []
    solids = rep.get("solids", [rep])
    out = []
    for name, title in HISTOGRAMS.items():
        hists = [s["histograms"][name] for s in solids if name in s.get("histograms", {})]
        if not hists:
            continue
        edges = hists[0]["edges"]
        counts = [sum(c) for c in zip(*(h["counts"] for h in hists), strict=True)]
        out.append(histogram_svg(edges, counts, title))
    return out


def histogram_svg(edges: Sequence[float], counts: Sequence[int], title: str) -> str:
    """A bar chart (inline SVG, 320 x 150 px) of ``counts`` over the bins ``edges``."""
    e = html.escape
    w, h, top, bottom, left = 320, 150, 22, 20, 8
    n = len(counts)
    peak = max(max(counts), 1)
    bw = (w - 2 * left) / n
    bars = []
    for k, c in enumerate(counts):
        bh = (h - top - bottom) * c / peak
        x, y = left + k * bw, h - bottom - bh
        tip = f"{edges[k]:g} to {edges[k + 1]:g}: {c} quads"
        bars.append(
            f'<rect x="{x:.1f}" y="{y:.1f}" width="{bw - 1:.1f}" height="{bh:.1f}" '
            f'fill="#4a7fc0"><title>{e(tip)}</title></rect>'
        )
    total = sum(counts)
    return (
        f'<svg class="hist" width="{w}" height="{h}" viewBox="0 0 {w} {h}" '
        f'role="img" aria-label="{e(title)}">'
        f'<text x="{w / 2}" y="14" text-anchor="middle" font-size="12">{e(title)}, '
        f"{total} quads</text>{''.join(bars)}"
        f'<line x1="{left}" y1="{h - bottom}" x2="{w - left}" y2="{h - bottom}" stroke="#444"/>'
        f'<text x="{left}" y="{h - 5}" font-size="11">{edges[0]:g}</text>'
        f'<text x="{w - left}" y="{h - 5}" font-size="11" text-anchor="end">{edges[-1]:g}</text>'
        "</svg>"
    )
