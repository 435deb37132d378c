"""The HTML of the reports: one page with its styles inline, tables of dict rows, figures
embedded as base64 PNG (and saved as PNG and SVG beside the page)."""

from __future__ import annotations

import base64
import html
import io
import re
from pathlib import Path

import numpy as np

from tiremodal_cli.workflow.manifest import provenance

__all__ = ["escape", "number", "table", "page", "written_by", "render", "img"]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:2em auto;max-width:1100px;
color:#222;line-height:1.4;padding:0 1em}
h1{font-size:1.5em;border-bottom:2px solid #345;padding-bottom:.2em}h2{font-size:1.2em;margin-top:1.6em;color:#345}
table{border-collapse:collapse;font-size:.85em;margin:.5em 0}td,th{border:1px solid #ccc;padding:.2em .5em;
text-align:right}th{background:#eef2f6}td.l,th.l{text-align:left}figure{margin:1em 0}
figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:.85em;color:#555}
.gifs{display:flex;flex-wrap:wrap;gap:.3em}.gifs figure{margin:0;width:150px}
.gifs img{width:150px;border:none}.gifs figcaption{font-size:.7em}
.ok{color:#161}.bad{color:#a11}.muted{color:#777;font-size:.85em}
"""


def escape(x) -> str:
    """Text for HTML (None as nothing)."""
    return html.escape("" if x is None else str(x))


def number(v, fmt="{:.4g}") -> str:
    """A number for a table cell (``fmt``); None, NaN and ±inf as nothing; text escaped."""
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return ""
    return fmt.format(v) if isinstance(v, (int, float)) else escape(v)


def table(rows: list[dict], cols: list[tuple[str, str]], *, left=()) -> str:
    """An HTML table of dict rows; cols = [(key, heading)]; ``left`` columns left-aligned."""
    def cell(tag, k, v):
        return f'<{tag} class="l">{v}</{tag}>' if k in left else f"<{tag}>{v}</{tag}>"

    def text(v):
        return escape(v) if isinstance(v, str) else number(v)
    head = "".join(cell("th", k, escape(h)) for k, h in cols)
    body = "".join("<tr>" + "".join(cell("td", k, text(r.get(k))) for k, _ in cols) + "</tr>" for r in rows)
    return f"<table>{f'<tr>{head}</tr>' if any(h for _, h in cols) else ''}{body}</table>"


def _anchor(m) -> str:
    """A heading matched by :func:`page` with an id made of its words."""
    slug = re.sub(r"[^a-z0-9]+", "-", html.unescape(re.sub(r"<[^>]+>", "", m.group(2))).lower()).strip("-")
    return f'<{m.group(1)} id="{slug}">{m.group(2)}</{m.group(1)}>'


def page(title: str, body: str, footer: str = "") -> str:
    """The page: every h2/h3 gets an id from its words (``#stabilization-diagram``) to link to."""
    body = re.sub(r"<(h[23])>(.*?)</\1>", _anchor, body)
    footer = re.sub(r"<(h[23])>(.*?)</\1>", _anchor, footer)
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{escape(title)}</title>'
            f"<style>{_CSS}</style></head><body>\n{body}\n"
            f'<footer class="muted">{footer or escape(written_by())}</footer></body></html>\n')


def written_by() -> str:
    """When and by which tiremodal (version, commit) the page was written."""
    p = provenance()
    return (f"Page written {p['created_utc']} by tiremodal {p['tiremodal_version']}"
            + (f" (commit {p['tiremodal_commit']})" if p.get("tiremodal_commit") else "") + ".")


def render(fig, folder: Path, stem: str) -> bytes:
    """Save ``fig`` as folder/stem.png and .svg; return the PNG bytes (for embedding)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    png = buf.getvalue()
    (folder / f"{stem}.png").write_bytes(png)
    fig.savefig(folder / f"{stem}.svg", format="svg")
    return png


def img(png: bytes, caption: str) -> str:
    """A figure embedded in the page (base64 PNG) with its caption."""
    b64 = base64.b64encode(png).decode("ascii")
    return (f'<figure><img alt="{escape(caption)}" src="data:image/png;base64,{b64}">'
            f"<figcaption>{escape(caption)}</figcaption></figure>")
