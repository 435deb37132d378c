"""Tables out: CSV text of rows (:func:`rows_to_csv`, also the commands'), and ``batch``'s
summary — one record per test, written as ``summary.csv`` (flat rows) and ``summary.jsonl``
(the records), with the campaign figures; read back by ``report``.

Light on purpose (no numerical imports): every command may import it at start-up.
"""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Sequence
from pathlib import Path

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import dumps, write_text_atomic

__all__ = ["SUMMARY_CSV", "SUMMARY_JSONL", "summary_rows", "rows_to_csv", "write_summary", "read_summary"]

SUMMARY_CSV = "summary.csv"
SUMMARY_JSONL = "summary.jsonl"

_SCALARS = ("test", "file", "kind", "status", "reason", "tire", "inflation_pressure", "n_points", "n_hits",
            "rejected_hits", "modes_found", "orders_mix")
_TAIL = ("adopted_effects", "parameter_off", "rms_error_pct", "rms_before_pct", "rms_after_pct", "verdict",
         "seconds", "output")


def summary_rows(records: Sequence[dict]) -> tuple[list[dict], list[str]]:
    """Flat rows for the CSV: identified parameters as ``NAME`` and ``NAME_std_error``
    columns, effect parameters of the final model as ``EFFECT.PARAM``, lists joined by ";".

    Returns rows and the column names (the union over the tests, in a stable order).
    """
    pcols, ecols = [], []
    for r in records:
        for k in (r.get("identified") or {}):
            if k not in pcols:
                pcols.append(k)
        for k in (r.get("augmented_parameters") or {}):
            if "." in k and k not in ecols:
                ecols.append(k)
    cols = list(_SCALARS) + [c for k in pcols for c in (k, f"{k}_std_error")] + ecols + list(_TAIL)
    rows = []
    for r in records:
        row = {k: r.get(k) for k in _SCALARS + _TAIL}
        for k in ("adopted_effects", "parameter_off"):
            row[k] = ";".join(r.get(k) or [])
        for k, v in (r.get("identified") or {}).items():
            row[k], row[f"{k}_std_error"] = v.get("value"), v.get("std_error")
        for k in ecols:
            v = (r.get("augmented_parameters") or {}).get(k)
            row[k] = v.get("value") if isinstance(v, dict) else v
        rows.append({k: ("" if row.get(k) is None else row.get(k)) for k in cols})
    return rows, cols


def rows_to_csv(rows, fieldnames=None) -> str:
    """CSV text of a list of dicts (header from the first row unless given)."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(fieldnames or rows[0]), lineterminator="\n", extrasaction="ignore")
    w.writeheader()
    w.writerows(rows)
    return buf.getvalue()


def write_summary(outdir, records: Sequence[dict], *, plots: bool = True) -> list[Path]:
    """Write ``summary.csv``, ``summary.jsonl`` and (``plots``) the campaign figures, each
    atomically. Returns the paths written."""
    outdir = Path(outdir)
    rows, cols = summary_rows(records)
    out = [write_text_atomic(outdir / SUMMARY_CSV, rows_to_csv(rows, cols), overwrite=True),
           write_text_atomic(outdir / SUMMARY_JSONL, "".join(dumps(r).replace("\n", "") + "\n" for r in records),
                             overwrite=True)]
    if plots and any(r["status"] in ("done", "skipped") for r in records):
        # here, not at the top (start-up): matplotlib only where figures are drawn; the commands import this module
        from tiremodal_cli.plots import plot_campaign_frequencies, plot_campaign_parameters, save_figure

        for name, make in (("campaign_parameters", plot_campaign_parameters),
                           ("campaign_frequencies", plot_campaign_frequencies)):
            for ext in ("png", "svg"):
                save_figure(make(records), outdir / f"{name}.{ext}", overwrite=True)
                out.append(outdir / f"{name}.{ext}")
    return out


def read_summary(outdir) -> list[dict]:
    """The records of a batch (``summary.jsonl``)."""
    p = Path(outdir) / SUMMARY_JSONL
    try:
        return [json.loads(line) for line in p.read_text(encoding="utf-8").splitlines() if line.strip()]
    except OSError:
        raise DataFormatError(f"{outdir}: no batch summary ({SUMMARY_JSONL}); run 'tiremodal batch' first") from None
    except ValueError as exc:
        raise DataFormatError(f"{p}: not JSON lines ({exc})") from None
