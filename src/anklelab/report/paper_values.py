"""What the two source papers report: the numbers the demo compares the twins against.

These are constants of the papers, each with the place it stands in the paper; nothing here is
measured. ``text`` is the value as the paper states it (with its qualifier or spread), ``value``
the number compared against (None where the paper gives none), in the units of the key's name.

Examples
--------
>>> PAPER_000["servo_natural_frequency_hz"].value
200.0
>>> PAPER_001["setpoint_time_s"].text
'within 300 ms'
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

__all__ = ["PAPER_000", "PAPER_001", "PaperValue"]


@dataclass(frozen=True)
class PaperValue:
    """A reported number: as printed, where, and the value compared (None if not numeric).

    Attributes
    ----------
    text : str
        The paper's statement, e.g. ``"≈200"`` or ``"96 (sd 3)"``.
    source : str
        Paper, section, table or figure.
    value : float or None
        The number compared against, in the unit named by the key.
    """

    text: str
    source: str
    value: float | None = None


_S21 = "paper 000, section 2.1"
_S241 = "paper 000, section 2.4.1"
_S31 = "paper 000, section 3.1"
_S32 = "paper 000, section 3.2"
_T2 = "paper 001, Table 2"

PAPER_000 = MappingProxyType(
    {
        "servo_natural_frequency_hz": PaperValue("≈200", f"{_S21}, Fig. 2", 200.0),
        "servo_gain_margin_db": PaperValue("8", _S21, 8.0),
        "servo_phase_margin_deg": PaperValue("45 (π/4 rad)", _S21, 45.0),
        "filter_vaf_percent": PaperValue("96 (sd 3)", _S31, 96.0),
        "onset_sd_ms_100": PaperValue("3.3", _S241, 3.3),
        "onset_sd_ms_225": PaperValue("3.2", _S241, 3.2),
        "onset_sd_ms_350": PaperValue("4.2", _S241, 4.2),
        "onset_sd_ms_475": PaperValue("5.2", _S241, 5.2),
        "stiffness_first_nm_per_rad": PaperValue("1277 (range start)", f"{_S32}, Fig. 8", 1277.0),
        "stiffness_last_nm_per_rad": PaperValue("860 (range end)", f"{_S32}, Fig. 8", 860.0),
        "model_vaf_percent": PaperValue("99.1 (sd 0.7)", f"{_S32}, Fig. 7b", 99.1),
        "inertia_kgm2": PaperValue("0.30 (sd 0.016)", _S32, 0.30),
        "window_75_change_percent": PaperValue("5 (sd 0.7)", _S32, 5.0),
        "window_125_change_percent": PaperValue("1 (sd 0.6)", _S32, 1.0),
        "bench_stiffness_near_nm_per_rad": PaperValue("1300 at 6 cm", _S32, 1300.0),
        "bench_stiffness_far_nm_per_rad": PaperValue("975 at 11 cm", _S32, 975.0),
        "bench_r2": PaperValue("0.96 (sd 0.05)", _S32, 0.96),
        "walking_vs_bench_error_percent": PaperValue(
            "5.4 mean, 3.6–8.4 (sd 0.7)", "paper 000, section 3.2 (three greatest distances)", 5.4
        ),
    }
)
"""Paper 000 (the Perturberator): servo loop, platform filters, walking and bench results."""

PAPER_001 = MappingProxyType(
    {
        "setpoint_time_s": PaperValue("within 300 ms", "paper 001, section 3.2, Fig. 4", 0.300),
        "chirp_bandwidth_hz": PaperValue(
            "good tracking up to ≈3 Hz", "paper 001, section 3.2, Fig. 5", 3.0
        ),
        "inertia_kgm2": PaperValue("7.540e-4", _T2, 7.540e-4),
        "viscous_cw_nms_per_rad": PaperValue("6.312e-4", _T2, 6.312e-4),
        "viscous_ccw_nms_per_rad": PaperValue("6.011e-4", _T2, 6.011e-4),
        "coulomb_cw_nm": PaperValue("0.0350", _T2, 0.0350),
        "coulomb_ccw_nm": PaperValue("0.0380", _T2, 0.0380),
        "stribeck_velocity_rad_s": PaperValue("3.2", _T2, 3.2),
        "static_friction_nm": PaperValue("0.045", _T2, 0.045),
        "observer": PaperValue("planned (ref. 8)", "paper 001, sections 1 and 4: no result yet"),
    }
)
"""Paper 001 (the capstan platform): set-point and chirp control, Table 2's friction."""
