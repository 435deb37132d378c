"""``tiremodal report``: the sample's report opens with every figure present and decodable."""

from __future__ import annotations

import base64
import io
import json
import os
import xml.etree.ElementTree as ET
from html.parser import HTMLParser
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from tiremodal_cli.workflow.batch import load_config, run_batch
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.workflow.pipeline import run
from tiremodal_cli.workflow.report import FIGURES, report
from tiremodal_cli.tyre.simulate import simulate_campaign

from conftest import run_cli

SAMPLE = Path(__file__).resolve().parents[1] / "sample_data" / "gl073a_sim.h5"


class _Page(HTMLParser):
    """Images, headings, links, table rows and any external reference of a page."""

    def __init__(self):
        super().__init__()
        self.images, self.headings, self.links, self.external, self.rows = [], [], [], [], 0
        self._h = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a.get("src", ""))
        if tag == "a":
            self.links.append(a.get("href", ""))
        if tag == "tr":
            self.rows += 1
        if tag in ("script", "link", "iframe") or any(
                k in ("src", "href") and v and v.startswith(("http:", "https:", "//", "file:"))
                for k, v in attrs):
            self.external.append((tag, attrs))
        if tag in ("h1", "h2", "h3"):
            self._h = ""

    def handle_data(self, data):
        if self._h is not None:
            self._h += data

    def handle_endtag(self, tag):
        if tag in ("h1", "h2", "h3") and self._h is not None:
            self.headings.append(self._h.strip())
            self._h = None


def _parse(path: Path) -> _Page:
    p = _Page()
    p.feed(path.read_text(encoding="utf-8"))
    return p


def _decode_png(src: str) -> np.ndarray:
    head, b64 = src.split(",", 1)
    assert head == "data:image/png;base64"
    return mpimg.imread(io.BytesIO(base64.b64decode(b64, validate=True)), format="png")


@pytest.fixture(scope="module")
def sample_run(tmp_path_factory):
    """The README's main job on the sample (the whole pipeline, default options), reported."""
    out = tmp_path_factory.mktemp("report") / "gl073a"
    summary = run(SAMPLE, out)
    res = run_cli(["report", out])
    assert res.exit_code == 0, res.output
    return out, summary


def test_sample_report_has_every_figure(sample_run):
    out, summary = sample_run
    page = _parse(out / "report.html")
    pngs = [s for s in page.images if s.startswith("data:image/png")]
    gifs = [s for s in page.images if s.startswith("data:image/gif")]
    assert len(pngs) == len(FIGURES) and len(gifs) == summary["modes_found"] == len(page.images) - len(pngs)
    for src in pngs:
        img = _decode_png(src)
        assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 300
        assert img[..., :3].std() > 0.01  # not a blank canvas
    assert page.external == []  # self-contained
    for stem, _ in FIGURES:
        png = mpimg.imread(out / "figures" / f"{stem}.png")
        assert png.shape[0] > 200
        root = ET.parse(out / "figures" / f"{stem}.svg").getroot()
        assert root.tag.endswith("svg")
    for title in ("Test", "Rejected hits (2)", "FRFs and coherence", "Stabilization diagram", "Modal table",
                  "MAC matrix", "Mode shapes", "Measured against synthesised FRFs", "Model identification",
                  "Residual diagnosis", "Candidates", "Predictions", "Parameter sensitivity"):
        assert title in page.headings, title
    text = (out / "report.html").read_text(encoding="utf-8")
    assert "double hit" in text and "clipped (overloaded) response" in text  # the sample's two bad hits
    assert "sidewall_membrane" in text and summary["verdict"].split(":")[0] in text
    # the modal table lists every mode of modes.csv
    n_modes = len((out / "modes.csv").read_text().splitlines()) - 1
    assert n_modes == summary["modes_found"] and f"<td>{n_modes}</td>" in text
    # the paper's comparison: the coupled model beside the flexible tread, by branch; the
    # flexible tread (one mode per order) cannot follow the opposite-direction branch
    assert "Where each model holds" in text and "flexible tread on an elastic foundation" in text
    cmp = json.loads((out / "identify.json").read_text())["model_comparison"]
    assert (cmp["flexible_tread"]["by_branch"]["opposite"]["rms_error_pct"]
            > 2 * cmp["coupled"]["by_branch"]["opposite"]["rms_error_pct"])
    assert "free: the rim channel (rim) moves" in text  # the sample's rim is on a 1,000 kg fixture


def test_report_mode_animations_and_size(sample_run):
    """One looping GIF per mode (decodable, moving: its frames differ), in the page and in
    figures/modes/; the whole page under 10 MB (the issue's bound for a 34-mode report)."""
    from PIL import Image

    out, summary = sample_run
    page = _parse(out / "report.html")
    gifs = [s for s in page.images if s.startswith("data:image/gif")]
    assert len(gifs) == summary["modes_found"] >= 34
    assert (out / "report.html").stat().st_size < 10e6
    im = Image.open(io.BytesIO(base64.b64decode(gifs[3].split(",", 1)[1])))
    assert im.n_frames >= 8
    frames = []
    for i in (0, im.n_frames // 4):
        im.seek(i)
        frames.append(np.asarray(im.convert("L"), float))
    assert np.abs(frames[0] - frames[1]).mean() > 0.1  # the rings move
    assert len(list((out / "figures" / "modes").glob("mode_*.gif"))) == summary["modes_found"]


def test_report_predictions_provenance_and_names(sample_run):
    """The predictions table's measured column holds the measured frequencies (Hz, of the
    diagnosis' modes), not flags; the footer says when, with what commit, by which command,
    with which options and from which input (full SHA-256); parameters carry names and units."""
    import html
    import re

    out, summary = sample_run
    text = (out / "report.html").read_text(encoding="utf-8")
    d = json.loads((out / "diagnosis.json").read_text())
    man = json.loads((out / "run.json").read_text())
    sec = text[text.index('<h2 id="predictions">'):text.index('<h2 id="parameter-sensitivity">')]
    rows = re.findall(r"<tr><td>(\d+)</td><td class=\"l\">(\w+)</td><td>[^<]*</td><td>[^<]*</td><td>([^<]*)</td></tr>",
                      sec)
    assert len(rows) == len(d["predictions"]["augmented"])
    seen = 0
    for n, br, meas in rows:
        want = sorted(m["measured_hz"] for m in d["modes"] if m["n"] == int(n) and m["branch"] == br)
        got = [float(x) for x in meas.split(";") if x.strip()]
        assert got == pytest.approx(want, rel=1e-3), (n, br)
        seen += bool(want)
    assert seen >= 20
    foot = text[text.index('<h2 id="provenance">'):]
    assert man["input_sha256"] in foot and man["created_utc"] in foot and "exp_end = 0.05" in foot
    # (the page escapes it: pytest's own argv may hold quotes, e.g. -k 'not digest')
    assert html.escape(man["command"]) in foot or "not recorded" in foot
    for words in ("tread–sidewall radial stiffness per length k_r1 [N/m²]", "tread bending stiffness EI [N·m²]",
                  "sidewall circumferential (membrane) stiffness", "sidewall membrane tension T_s [N]"):
        assert words in text, words


def test_predictions_reach_beyond_the_measured_orders(sample_run):
    out, _ = sample_run
    d = json.loads((out / "diagnosis.json").read_text())
    n_meas = max(m["n"] for m in d["modes"])
    assert max(p["n"] for p in d["predictions"]["augmented"]) == max(12, n_meas + 2)


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_batch_index_links_every_report(tmp_path):
    tree = tmp_path / "tree"
    simulate_campaign(tree, [7e5, 9e5], seed=7)
    (tree / "broken.h5").write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100))
    out = tmp_path / "out"
    recs = run_batch([tree], out, load_config(None, run_overrides={"max_effects": 0}))
    assert [r["status"] for r in recs] == ["failed", "done", "done"]
    res = run_cli(["report", out, "--json"])
    assert res.exit_code == 0, res.output
    pages = [Path(p) for p in json.loads(res.stdout)["pages"]]
    assert pages[-1] == out / "index.html" and len(pages) == 3
    index = _parse(out / "index.html")
    assert sorted(index.links) == ["p0700_r1/report.html", "p0900_r1/report.html"]
    assert all((out / link).is_file() for link in index.links)
    assert index.rows == 4 and len(index.images) == 2 and index.external == []
    for src in index.images:
        assert _decode_png(src).shape[0] > 200
    assert "not a readable HDF5 file" in (out / "index.html").read_text()
    assert (out / "figures" / "campaign_parameters.svg").is_file()


def test_report_of_a_folder_that_is_not_a_run(tmp_path):
    with pytest.raises(DataFormatError, match="neither a run folder"):
        report(tmp_path)
    res = run_cli(["report", tmp_path / "nope"])
    assert res.exit_code == 2
    assert res.stderr.strip() == f"Error: {tmp_path / 'nope'}: no such folder"


def test_the_sample_run_has_one_base_fit(sample_run):
    """issue #15: identify makes the base fit and hands it to diagnose; identify.json,
    diagnosis.json, run.json and the report hold the same numbers."""
    out, summary = sample_run
    ident = json.loads((out / "identify.json").read_text())
    diag = json.loads((out / "diagnosis.json").read_text())
    assert ident["rms_error_pct"] == diag["base"]["rms_error_pct"] == summary["rms_before_pct"] \
        == summary["rms_error_pct"]
    for name, v in ident["parameters"].items():
        assert diag["base"]["parameters"][name]["value"] == v["value"]
        assert summary["identified"][name]["value"] == v["value"]
    assert ident["set_aside"] == diag["set_aside_before"] == summary["set_aside_modes"]
    text = (out / "report.html").read_text(encoding="utf-8")
    assert f"{ident['rms_error_pct']:.3f} %" in text
    assert "Modes set aside" in text


def test_report_in_a_real_browser(sample_run, tmp_path):
    """The page in headless Chromium: it loads with no console error or warning, no
    exception and no failed load (a page that logs an error is caught: the check can
    fail), every image decodes, nothing overflows the width; screenshots taken.
    ``TIREMODAL_SCREENSHOTS=docs/images`` writes them (as small palette PNGs) for
    docs/report.md."""
    from browser import CHROMIUM, Browser

    if not CHROMIUM.exists():
        pytest.skip(f"Debian's Chromium is not installed ({CHROMIUM} absent; CI machines have none): "
                    "apt-get install chromium to run the browser check")
    out, summary = sample_run
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><body><p>x</p><script>console.error("planted")</script></body></html>')
    shots = tmp_path / "shots"
    shots.mkdir()
    with Browser(width=1150, height=900) as b:
        b.open(bad.as_uri())
        assert any("planted" in p for p in b.problems)  # the check sees a console error
        b.open((out / "report.html").as_uri())
        assert b.problems == []
        assert b.js("document.title").startswith("tiremodal report")
        assert b.js("document.images.length") == len(FIGURES) + summary["modes_found"]
        assert b.js("Array.from(document.images).filter(i => !(i.complete && i.naturalWidth > 0)).length") == 0
        assert b.js("document.documentElement.scrollWidth <= window.innerWidth")
        files = [b.screenshot(shots / "report_top.png"),
                 b.screenshot(shots / "report_stabilization.png", element_id="stabilization-diagram", height=1080),
                 b.screenshot(shots / "report_modes_moving.png", element_id="the-modes-moving", height=560)]
    for f in files:
        img = mpimg.imread(f)
        assert img.shape[1] >= 1100 and img.shape[0] >= 500 and img[..., :3].std() > 0.05
    dest = os.environ.get("TIREMODAL_SCREENSHOTS")
    if dest:
        from PIL import Image

        for f in files:
            im = Image.open(f).convert("RGB")
            im = im.resize((im.width * 3 // 4, im.height * 3 // 4), Image.Resampling.LANCZOS)
            im.convert("P", palette=Image.Palette.ADAPTIVE, colors=64).save(Path(dest) / f.name, optimize=True)


def test_run_on_a_table_of_modes_reports_the_papers_comparison(tmp_path):
    """The paper's Table A1 (measured modes, no records) through ``run`` and ``report``: the
    pipeline starts at identify, the diagnosis closes 3.28 % to ≤ 1.2 % as ``diagnose``
    does, and the report holds the paper's comparison — the classical flexible tread fails
    the opposite branch (the paper: it holds only to 180 Hz) where the coupled model does not."""
    a1 = Path(__file__).resolve().parents[1] / "sample_data" / "paper_table_a1.csv"
    out = tmp_path / "a1"
    res = run_cli(["run", a1, "-o", out, "--json"])
    assert res.exit_code == 0, res.output
    s = json.loads(res.stdout)
    assert s["starts_at"] == "identify" and s["modes_found"] == 18 and s["rejected_hits"] == []
    assert s["rms_before_pct"] == pytest.approx(3.28, abs=0.02) and s["rms_after_pct"] <= 1.2
    assert sorted(p.name for p in out.iterdir()) == ["diagnosis.json", "identify.json", "modes.csv", "run.json",
                                                     "sensitivity.json"]
    cmp = json.loads((out / "identify.json").read_text())["model_comparison"]
    flex, coupled = cmp["flexible_tread"]["by_branch"], cmp["coupled"]["by_branch"]
    f_opp, c_opp = flex["opposite"]["rms_error_pct"], coupled["opposite"]["rms_error_pct"]
    assert f_opp > 10 * c_opp and f_opp > 20 and c_opp < 5
    res = run_cli(["report", out])
    assert res.exit_code == 0, res.output
    text = (out / "report.html").read_text()
    assert "started at identify" in text and "flexible tread on an elastic foundation" in text
    page = _Page()
    page.feed(text)
    assert not page.external and len(page.images) >= 5


def test_a_test_with_mixed_orders_says_so_in_its_report(sample_run):
    """The report's modal table carries the note of a test whose orders mix (modal.mixing)
    and none on the sample, whose orders do not mix."""
    import html

    from tiremodal_cli.modal.mixing import mixed_orders_note
    from tiremodal_cli.workflow.run_page import run_body

    out, _ = sample_run
    man = json.loads((out / "run.json").read_text(encoding="utf-8"))
    ident, diag = (json.loads((out / f).read_text(encoding="utf-8")) for f in ("identify.json", "diagnosis.json"))
    pngs = {stem: b"png" for stem, _ in FIGURES}
    assert man["summary"]["orders_mix"] is None
    assert "Completeness" not in run_body(out, man, ident, diag, pngs)
    man["summary"]["orders_mix"] = note = mixed_orders_note(0.2, None)
    assert note["statement"] in html.unescape(run_body(out, man, ident, diag, pngs))
