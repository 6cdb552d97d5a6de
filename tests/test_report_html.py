"""The self-contained HTML report, checked in a real headless browser."""

import numpy as np
from matplotlib.figure import Figure as MplFigure

from anklelab.report import Figure, Section, Table, figure_png, write_report
from tests.browser import view


def sample_report(tmp_path):
    fig = MplFigure()
    ax = fig.subplots()
    t = np.linspace(0, 1, 200)
    ax.plot(t, np.sin(2 * np.pi * 3 * t))
    sections = [
        Section(
            "Results",
            "First paragraph.\n\nSecond <paragraph> & more.",
            [Table("Numbers", ["name", "value"], [["k", 1234.5678], ["b", 2]])],
            [Figure("A sine", figure_png(fig), "Three hertz.")],
        )
    ]
    return write_report(tmp_path / "report.html", "Test report", sections, {"version": "x"})


def test_report_is_self_contained_and_escapes_text(tmp_path):
    page = sample_report(tmp_path).read_text()
    assert "data:image/png;base64," in page
    assert "http://" not in page and "https://" not in page and "<script" not in page
    assert "Second &lt;paragraph&gt; &amp; more." in page
    assert "<td>1235</td>" in page


def test_report_renders_in_headless_chromium(tmp_path):
    seen = view(sample_report(tmp_path), "report_html_sample.png")
    assert seen.console_errors == []
    assert len(seen.images) == 1
    assert all(img["complete"] and img["width"] > 0 and img["height"] > 0 for img in seen.images)
    assert seen.screenshot.stat().st_size > 1000
