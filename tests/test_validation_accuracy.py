"""The accuracy harness: protocols other than the drawn one reach the clean-room generator, and
a malformed protocol item is named before any session is generated."""

from __future__ import annotations

import pytest
from validation.accuracy import generate, main, parse_protocol


def test_a_changed_protocol_reaches_the_clean_room_session():
    protocol = parse_protocol(
        [
            "sample_rate_hz=2000",
            "timing_points_ms=(150.0, 300.0)",
            "onset_jitter_sd_s=(0.003, 0.004)",
            "trials_per_point=2",
            "n_unperturbed=3",
            "n_calibration=1",
        ]
    )
    session = generate("cleanroom", "nominal", 100, protocol)
    assert session.info.sample_rate_hz == 2000.0
    assert len(session.walking) == 2 * 2 + 3
    assert {t.delay_ms for t in session.walking if t.perturbed} == {150.0, 300.0}
    assert sorted(session.truth["reference"]["dorsi"]) <= ["150", "300"]


@pytest.mark.parametrize(
    "item", ["trials_per_point", "trials_per_pont=3", "ramp_s=fast", "=0.05", "ramp_s=(0.05"]
)
def test_a_malformed_protocol_item_is_named(item):
    with pytest.raises(SystemExit, match=rf"--protocol: .*got '{item.replace('(', '[(]')}'"):
        parse_protocol([item])


def test_a_protocol_is_checked_whole_before_anything_is_generated():
    with pytest.raises(SystemExit, match=r"--protocol: onset_jitter_sd_s: expected one value"):
        parse_protocol(["timing_points_ms=(150.0, 300.0, 450.0)"])


def test_the_twin_takes_no_protocol():
    """Refused before the sessions are handed to worker processes (where an exit would be lost
    and the pool would wait for it forever)."""
    with pytest.raises(SystemExit, match="only the cleanroom generator"):
        main(["--generator", "twin", "--sessions", "1", "--protocol", "ramp_s=0.05"])
    with pytest.raises(ValueError, match="only the cleanroom generator"):
        generate("twin", "random", 0, (("ramp_s", 0.05),))


def test_an_analysis_window_other_than_the_truths_is_refused(tmp_path):
    """Both generators' truth is a 100 ms average: a 125 ms analysis scored against it reads a
    changing stiffness's difference between the windows as error."""
    settings = tmp_path / "s.toml"
    settings.write_text("window_ms = 125.0\n")
    with pytest.raises(SystemExit, match="window_ms = 125; the generators' truth"):
        main(["--generator", "cleanroom", "--sessions", "1", "--settings", str(settings)])
