"""The run's report as one self-contained HTML file (no network): a sortable table of the
parts, the kept-blend reasons grouped over the run, and each part's pictures inlined.

Pictures are the PNG views the steps wrote (``medax batch --pictures``), embedded as
``data:`` URIs; the sorting is a few lines of inline JavaScript.
"""

from __future__ import annotations

import base64
import html
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

_STYLE = """
body{font:14px system-ui,sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse}th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}
th{background:#eee;cursor:pointer;user-select:none}td:first-child,td:nth-child(2){text-align:left}
tr.ok td:nth-child(2){color:#060}tr.refused td:nth-child(2){color:#a60}
tr.failed td:nth-child(2),tr.timeout td:nth-child(2){color:#b00;font-weight:bold}
section{margin:1.5em 0;border-top:1px solid #ccc}img{max-width:32%;margin:4px;border:1px solid #ddd}
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
    """The report's text; pictures are read from ``outdir``."""
    e = html.escape
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
    parts = [_part_section(r, Path(outdir)) for r in records]
    heading = "".join(f"<th>{e(h)}</th>" for h, _ in COLUMNS)
    return (
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        f"<title>medax batch: {e(str(outdir))}</title><style>{_STYLE}</style></head><body>"
        f"<h1>medax batch</h1><p>{e(head)}</p>"
        f"<table><thead><tr>{heading}</tr></thead><tbody>{''.join(rows)}</tbody></table>"
        "<h2>Kept blends, by reason</h2>"
        + (
            f"<table><thead><tr><th>reason</th><th>blends</th></tr></thead>"
            f"<tbody>{reasons}</tbody></table>"
            if reasons
            else "<p>none</p>"
        )
        + "<h2>Parts</h2>"
        + "".join(parts)
        + f"<script>{_SORT}</script></body></html>\n"
    )


def write_report(
    records: Sequence[Mapping[str, Any]], summary: Mapping[str, Any], outdir: str | Path
) -> Path:
    """Write ``outdir/report.html`` atomically."""
    from medax.io_utils import atomic_path

    text = report_html(records, summary, outdir)
    path = Path(outdir) / REPORT
    with atomic_path(path, "report") as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def _part_section(r: Mapping[str, Any], outdir: Path) -> str:
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
    files = [*outputs.values(), f"{r['part_dir']}/batch.log"]
    links = " ".join(f'<a href="{e(p)}">{e(Path(p).name)}</a>' for p in files)
    return (
        f'<section id="{e(r["part_dir"])}"><h3>{e(r["part_dir"])}</h3>'
        f"<p>{'<br>'.join(lines)}</p><p>{links}</p>{''.join(imgs)}</section>"
    )
