"""The HTML diagnosis report: one self-contained page whose tables say what the report says,
whose plots draw in a real headless browser (Debian's Chromium) with no console error and
no request off the file system, and the ``--report`` option of ``bondgraph diagnose``.

The diagnosis is the third-party square-law candidate of tests/test_diagnose.py on its lag
record (a first-order lag driven through u + 0.4·u²): one named cause, in seconds.  The real
P-885 record's report is written and opened in tests/test_diagnose.py.
"""

from __future__ import annotations

import re
from html.parser import HTMLParser

import numpy as np
import pytest
from browser import assert_plots_drawn, open_page
from conftest import MODELS
from scipy.signal import welch
from test_diagnose import SquareLaw, lag_model, lag_record

from bondgraph.cli import main
from bondgraph.diagnosis import diagnose
from bondgraph.diagnosis.display import chain_table, headline, report_html
from bondgraph.plotting.html_report import curves, noise_psd, report_page, write_report

pytest.importorskip("bokeh")


@pytest.fixture(scope="module")
def square():
    """The lag record with a square-law drive term, diagnosed with the square-law candidate."""
    return diagnose(lag_model(), lag_record(square=0.4), candidates=[SquareLaw()], workers=1)


def test_the_page_is_self_contained_and_says_what_the_report_says(square, tmp_path):
    rep = square
    path = tmp_path / "report.html"
    write_report(rep, path)
    page = path.read_text()
    assert not outside_links(page)  # no script, style or image from the network
    assert "Bokeh" in page and 'id="plots"' in page  # the library inline, the plots' root
    chain = re.search(r'id="chain">Chain: <b>(.*?)</b>', page).group(1)
    assert chain == f"square-law ×{rep.steps[0].gain:.3g}"
    assert f"total gain ×{rep.gain:.3g}" in page
    # the parameters with their units: the calibrated time constant, the added coefficient
    assert re.search(
        r"<td>tau</td><td class=\"num\">{}</td>".format(re.escape(f"{rep.calibration['params']['tau']:.4g}")), page
    )
    assert re.search(r"<td>sq\.a</td><td class=\"num\">[^<]+</td><td></td><td></td><td>1/V</td>", page)
    assert f"{rep.steps[0].candidates[0].params['sq.a']:.4g}" in page
    assert 'class="bondgraph"' in page  # the extended bond graph, drawn with its causal strokes
    assert page.count('class="stroke"') == len(rep.extended_model.bonds)


def outside_links(page: str) -> list[str]:
    """The ``src`` and ``href`` attributes of the page's tags that point off the file system."""
    found = []

    class Links(HTMLParser):
        def handle_starttag(self, tag, attrs):
            found.extend(v for k, v in attrs if k in ("src", "href") and v and re.match(r"(https?:)?//", v))

    Links().feed(page)
    return found


def test_the_residual_after_the_chain_lies_on_the_noise_floor(square):
    """The record's noise is white (σ = 2 mV); once the square law is named the residual is that
    noise, so its spectrum above the drive's band sits on the noise floor the page draws."""
    p = square.predictions
    fs = square.data["rate_hz"]
    f, pxx = welch(p["y"] - p["extended"], fs=fs, nperseg=512)
    above = f > 2 * square.data["drive_band_hz"]
    assert square.noise == pytest.approx(0.002, rel=0.1)
    assert np.median(pxx[above]) == pytest.approx(noise_psd(square.noise, fs), rel=0.3)
    f, pxx = welch(p["y"] - p["baseline"], fs=fs, nperseg=512)
    assert np.median(pxx[f < square.data["drive_band_hz"]]) > 1e3 * noise_psd(square.noise, fs)  # before: far above


def test_a_diagnosis_that_names_nothing_has_its_page_too():
    """On the effect-free lag record nothing is named: the page shows the calibrated model
    alone, the chain 'none' and why the chain stopped, and no extended bond graph."""
    rep = diagnose(lag_model(), lag_record(square=0.0), candidates=[SquareLaw()], workers=1)
    assert rep.causes == []
    page = report_page(rep)
    assert re.search(r'id="chain">Chain: <b>none</b>', page)
    assert [label for label, _ in curves(rep)] == ["calibrated model"]
    assert '<tr class="stop"><td>stop</td><td>none</td>' in page and 'class="bondgraph"' not in page


def test_fields_a_report_may_carry_are_shown_when_present(square, monkeypatch):
    """The deciding rule, the site, the unexplained shares and a step's noise floor appear
    when the report's JSON has them, and their columns are left out when it does not."""
    j = square.as_json()
    bare = {k: v for k, v in j.items() if k not in ("unexplained_share", "unexplained_linear_share")}
    bare["steps"] = [{k: v for k, v in s.items() if k not in ("rule", "site")} for s in j["steps"]]
    assert "deciding rule" not in chain_table(bare) and "unexplained share" not in headline(bare)
    j["steps"][0] |= {"rule": "gain over the flexible linear reference", "site": "drive", "unexplained_share": 0.125}
    j |= {"unexplained_share": 0.08, "unexplained_linear_share": 0.5}
    table, head = chain_table(j), headline(j)
    assert "<th>deciding rule</th>" in table and "<td>gain over the flexible linear reference</td>" in table
    assert "<th>site</th>" in table and "<td>drive</td>" in table and "12.5 %" in table
    assert "unexplained share 8 %; of it linear 50 %" in head
    monkeypatch.setattr(square, "as_json", lambda: j)
    assert "12.5 %" in report_html(square) and "12.5 %" in report_page(square)


def test_the_noise_floor_is_the_level_of_white_noise_in_the_spectrum():
    """Welch's one-sided density of white noise of RMS σ sampled at fs averages 2σ²/fs."""
    rng = np.random.default_rng(1)
    sigma, fs = 0.3, 1000.0
    f, pxx = welch(rng.normal(0, sigma, 200_000), fs=fs, nperseg=1024)
    assert np.mean(pxx[1:-1]) == pytest.approx(noise_psd(sigma, fs), rel=0.02)


def test_each_step_is_drawn_when_the_report_keeps_them(square, monkeypatch):
    base, ext = square.predictions["baseline"], square.predictions["extended"]
    monkeypatch.delitem(square.predictions, "steps")
    assert [label for label, _ in curves(square)] == ["calibrated model", "extended (square-law)"]
    monkeypatch.setitem(square.predictions, "steps", [ext])
    (b, yb), (s, ys) = curves(square)
    assert (b, s) == ("calibrated model", "calibrated + square-law")
    assert np.array_equal(yb, base) and np.array_equal(ys, ext)


def test_the_report_opens_in_headless_chromium_with_its_plots(square, tmp_path):
    path, png = tmp_path / "report.html", tmp_path / "report.png"
    write_report(square, path)
    with open_page(path) as (page, log):
        canvases = page.eval_on_selector_all("canvas", "cs => cs.filter(c => c.width > 100 && c.height > 100).length")
        chain = page.inner_text("#chain")
        named = page.eval_on_selector_all("#chain-table tr.named", "rs => rs.map(r => r.cells[1].innerText)")
        params = page.eval_on_selector_all("#parameters tr", "rs => rs.map(r => r.cells[0].innerText)")
        page.screenshot(path=str(png), full_page=True)
    assert not log.problems(), log.problems()
    assert canvases >= 5  # the five plots drew
    assert chain.startswith("Chain: square-law ×") and named == ["square-law"]
    assert {"tau", "sq.a", "sensor gain"} <= set(params)
    assert_plots_drawn(png)


@pytest.mark.parametrize(
    "name,message",
    [("report.png", "must end in .html"), ("missing/report.html", "does not exist")],
)
def test_cli_refuses_a_bad_report_path_before_the_work(tmp_path, capsys, name, message):
    path = tmp_path / "data.csv"
    path.write_text("t,V,x\n0,0,0\n0.001,1,1e-7\n0.002,2,2e-7\n")
    assert main(["diagnose", str(MODELS / "apa120ml.py"), str(path), "--report", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--report" in err[0] and message in err[0]
    assert list(tmp_path.iterdir()) == [path]
