"""A tiny Perturberator twin session survives both storage formats exactly."""

import numpy as np

from anklelab.data import diff_sessions, load_session, read_directory, save_session, summarize
from anklelab.experiments import simulate_perturberator


def test_twin_session_round_trips_through_h5_and_directory(tmp_path):
    session = simulate_perturberator(
        trials_per_point=1, n_unperturbed=2, n_calibration=1, bench=True, seed=3
    )
    from_h5 = load_session(save_session(session, tmp_path / "twin.h5"))
    assert diff_sessions(from_h5, session) == []
    from_dir = read_directory(save_session(from_h5, tmp_path / "twin", format="dir"))
    assert diff_sessions(from_dir, session) == []
    # the walking analysis reads these through the contract's keys
    onset = from_dir.truth["trials"]["onset_s"]
    assert onset.shape == (len(session.walking),)
    assert np.isnan(onset[[not t.perturbed for t in session.walking]]).all()
    summary = summarize(from_dir)
    assert summary["walking"]["n_unperturbed"] == 2 and summary["truth"]
