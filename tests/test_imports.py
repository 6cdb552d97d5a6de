"""Each command and package loads only what it uses (package names load on first use)."""

import pytest

from anklelab.data import save_session
from anklelab.data._synthetic import random_session
from tests.module_loading import loaded

TWINS = ["numba", "llvmlite", "anklelab.sim", "anklelab.control", "anklelab.experiments"]
LAB_FORMATS = ["ezc3d", "anklelab.data.c3d", "anklelab.data.c3d_import", "anklelab.data.matlab_map"]
HEAVY = [*TWINS, *LAB_FORMATS, "scipy", "h5py", "matplotlib", "pyarrow"]


def test_importing_anklelab_and_its_packages_loads_nothing_heavy():
    modules = loaded(
        "import anklelab, anklelab.data, anklelab.ident, anklelab.signals, anklelab.report"
    )
    assert not modules & {*HEAVY, "numpy", "pydantic"}


def test_public_names_still_import_from_their_packages():
    from anklelab import PlateGeometry, __version__, load_platform
    from anklelab.data import load_session
    from anklelab.ident import FrictionIdentifier, PlatformFilters
    from anklelab.ident.friction import FrictionIdentifier as defined
    from anklelab.report import save_walking_figures
    from anklelab.signals import lowpass

    assert FrictionIdentifier is defined and callable(load_session) and __version__
    assert all(callable(f) for f in (PlateGeometry, load_platform, PlatformFilters))
    assert callable(save_walking_figures) and callable(lowpass)
    with pytest.raises(AttributeError, match="has no attribute 'nothing'"):
        import anklelab.ident

        anklelab.ident.nothing  # noqa: B018


def test_help_loads_no_implementation():
    assert not loaded("from anklelab.cli import run; run()", "--help") & {
        *HEAVY,
        "anklelab.data",
        "anklelab.ident",
        "anklelab.pipelines",
    }


@pytest.fixture(scope="module")
def sessions(tmp_path_factory):
    root = tmp_path_factory.mktemp("imports")
    session = random_session()
    return save_session(session, root / "s", format="dir"), save_session(session, root / "s.h5")


def test_session_info_and_import_load_no_analysis_or_twin(sessions, tmp_path):
    directory, h5 = sessions
    for argv in (
        ("session", "info", directory),
        ("session", "info", h5),
        ("import", directory, "--out", tmp_path / "x.h5"),
    ):
        modules = loaded("from anklelab.cli import run; run()", *argv)
        # pandas: pyarrow's to_numpy imports it (0.2 s), which the CSV reader does without
        unwanted = {*TWINS, *LAB_FORMATS, "scipy", "matplotlib", "anklelab.ident", "pandas"}
        assert not modules & unwanted, argv
    assert (tmp_path / "x.h5").exists()


def test_the_analysis_of_recorded_data_never_loads_numba_or_the_twins(sessions):
    _, h5 = sessions
    # the analysis path, as `anklelab analyze` imports it (the noise session itself is
    # rejected by the analysis; what matters is what the command loaded)
    modules = loaded(
        "from anklelab.cli import run; run()", "analyze", h5, "--out", h5.with_name("out")
    )
    assert "anklelab.pipelines.walking" in modules
    assert not modules & {*TWINS, *LAB_FORMATS, "anklelab.ident.friction", "matplotlib"}
    figures = loaded("import anklelab.report.figures_walking, anklelab.pipelines.walking")
    assert not figures & {*TWINS, "anklelab.ident.friction"}


def test_simulating_the_perturberator_loads_no_signal_processing_or_statistics(tmp_path):
    """scipy.signal (and scipy.stats, which it imports) cost a second of start-up; only the
    capstan's tracking model and the analysis use them."""
    out = tmp_path / "s.h5"
    modules = loaded(
        "from anklelab.cli import run; run()",
        *("simulate", "perturberator", "--out", out, "--trials-per-point", "2"),
        *("--unperturbed", "4"),
    )
    assert out.is_file()
    assert not modules & {"scipy.signal", "scipy.stats", "matplotlib"}


def test_analysing_a_walking_session_loads_no_scipy(tmp_path):
    """scipy.special (Student's t) and scipy.fft (which imports it) cost every analysis 0.13 s;
    NumPy's FFT and :mod:`anklelab._student_t` do their work."""
    from anklelab.experiments import simulate_perturberator

    session = simulate_perturberator(trials_per_point=8, n_unperturbed=16, n_calibration=2, seed=5)
    path = save_session(session, tmp_path / "s.h5")
    argv = ("analyze", path, "--out", tmp_path / "out", "--no-figures")
    modules = loaded("from anklelab.cli import run; run()", *argv)
    assert (tmp_path / "out" / "results.json").is_file()
    assert not any(name == "scipy" or name.startswith("scipy.") for name in modules)
