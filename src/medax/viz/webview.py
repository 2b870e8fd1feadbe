"""The interactive 3D view in HTML: a viewer element holding models (``view3d`` data of
[medax.cad.view_data][medax.cad.view_data]) and the WebGL script (``webview.js``, shipped with
medax) that draws them. Everything is inlined: the page loads nothing from the network.

[viewer_html][medax.viz.webview.viewer_html] gives the element (one viewer per page; a
selector switches between its models); [page][medax.viz.webview.page] a whole page;
[ERRORS_HTML][medax.viz.webview.ERRORS_HTML] the element and handler that record script
errors in the page, for headless tests.
"""

from __future__ import annotations

import html
import json
from collections.abc import Mapping, Sequence
from functools import cache
from importlib import resources
from typing import Any

STYLE = """
.mx-view{margin:1em 0;max-width:960px}
.mx-view canvas{width:100%;height:480px;border:1px solid #ccc;display:block;cursor:grab;
 touch-action:none}
.mx-bar{display:flex;gap:1em;align-items:center;flex-wrap:wrap;margin:4px 0;font-size:13px}
.mx-legend span{margin-right:10px;white-space:nowrap}
.mx-legend i{display:inline-block;width:11px;height:11px;margin-right:4px;border:1px solid #888;
 vertical-align:-1px}
.mx-info{font-size:13px;min-height:1.4em;font-family:ui-monospace,monospace}
#medax-errors{color:#b00;white-space:pre-wrap}
"""
ERRORS_HTML = (
    '<pre id="medax-errors" hidden></pre><script>window.addEventListener("error",function(e){'
    'var b=document.getElementById("medax-errors");b.hidden=false;b.appendChild('
    'document.createTextNode((e.message||"error")+" ("+(e.filename||"")+":"+(e.lineno||0)+")\\n"'
    "))});</script>"
)
"""First thing in ``<body>``: records script errors into the page (read by the headless
test)."""


@cache
def viewer_script() -> str:
    """Read the viewer's JavaScript (``medax/viz/webview.js``, cached)."""
    return (resources.files("medax.viz") / "webview.js").read_text(encoding="utf-8")


def _json_in_script(data: Mapping[str, Any]) -> str:
    """``data`` as JSON safe inside a <script> element."""
    return json.dumps(data, separators=(",", ":")).replace("</", "<\\/")


def viewer_html(models: Sequence[tuple[str, Mapping[str, Any]]], element_id: str = "view") -> str:
    """Build the viewer element with its models and script.

    Parameters
    ----------
    models : sequence of tuple
        ``(label, view data)`` per model; a selector switches between several.
    element_id : str
        The element's HTML id (one viewer per page).

    Returns
    -------
    str
        The HTML; empty text when there is no model.
    """
    if not models:
        return ""
    e = html.escape
    options = "".join(
        f'<option value="{k}">{e(label)}</option>' for k, (label, _) in enumerate(models)
    )
    select = f"<select>{options}</select>" if len(models) > 1 else f"<b>{e(models[0][0])}</b>"
    data = "".join(
        f'<script type="application/json" class="mx-model">{_json_in_script(m)}</script>'
        for _, m in models
    )
    return (
        f'<div class="mx-view" id="{e(element_id)}" data-status="loading">'
        f'<div class="mx-bar">{select}<span class="mx-legend"></span></div>'
        '<canvas></canvas><div class="mx-info">loading the 3D view</div>'
        '<div class="mx-bar" style="color:#666">drag: orbit; wheel: zoom; right-drag or '
        f"shift-drag: pan; click a face: what it is</div>{data}</div>"
        f"<script>{viewer_script()}</script>"
    )


def page(title: str, body: str, style: str = "") -> str:
    """Wrap a body into a whole HTML page with the viewer's style and the error recorder.

    Parameters
    ----------
    title : str
        The page title (escaped).
    body : str
        HTML of the body.
    style : str
        CSS added to the viewer's.

    Returns
    -------
    str
        The page.
    """
    return (
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">'
        f"<title>{html.escape(title)}</title><style>{STYLE}{style}</style></head>"
        f"<body>{ERRORS_HTML}{body}</body></html>\n"
    )


def view_page(models: Sequence[tuple[str, Mapping[str, Any]]], title: str) -> str:
    """Build a page with only the viewer (``medax classify/simplify --view3d FILE.html``).

    Parameters
    ----------
    models : sequence of tuple
        ``(label, view data)`` per model.
    title : str
        The page title and heading.

    Returns
    -------
    str
        The page.
    """
    body = f"<h2>{html.escape(title)}</h2>{viewer_html(models)}"
    return page(title, body, "body{font:14px system-ui,sans-serif;margin:1em}")
