"""Force-plate conventions (DESIGN.md section 3): static loads, round trips, GRF, ankle torque."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from anklelab.errors import EventNotFoundError
from anklelab.forceplate import (
    CHANNELS,
    PLATE_TYPES,
    GrfCopPlate,
    PlateGeometry,
    SagittalLoad,
    SixAxisPlate,
    ankle_torque,
    channels_from_load,
    plate_class,
    resultants,
    sagittal_load,
)

A, B, AZ0 = 0.12, 0.20, -0.045


def plate(anterior_axis="+x"):
    return PlateGeometry(a_m=A, b_m=B, az0_m=AZ0, anterior_axis=anterior_axis)


def channel_vector(**values):
    return np.array([values.get(name, 0.0) for name in CHANNELS])


SENSORS = {1: (A, B), 2: (-A, B), 3: (-A, -B), 4: (A, -B)}


@pytest.mark.parametrize("sensor", [1, 2, 3, 4])
def test_vertical_load_over_each_sensor_puts_cop_on_that_sensor(sensor):
    res = resultants(channel_vector(**{f"fz{sensor}": 500.0}), plate(), axis=0)
    assert res.fz == 500.0
    assert (res.ax, res.ay) == pytest.approx(SENSORS[sensor], abs=1e-12)


def test_load_shared_by_two_sensors_sits_between_them():
    # 300 N on sensor 1 and 100 N on sensor 2: the COP is 3/4 of the way from 2 to 1.
    res = resultants(channel_vector(fz1=300.0, fz2=100.0), plate(), axis=0)
    assert (float(res.ax), float(res.ay)) == pytest.approx((0.5 * A, B), abs=1e-12)


def test_horizontal_force_shifts_cop_by_the_surface_offset():
    # A pure vertical load at the centre plus a forward shear Fx, applied at the plate surface
    # (az0 above the sensors): the sensors see My = az0*Fx, and the COP stays at the centre.
    fx, fz = 50.0, 600.0
    d = AZ0 * fx / (4 * A)  # sensors 2 and 3 (rear, -a) carry +d, sensors 1 and 4 carry -d
    channels = channel_vector(
        fx12=fx / 2, fx34=fx / 2, fz1=fz / 4 - d, fz2=fz / 4 + d, fz3=fz / 4 + d, fz4=fz / 4 - d
    )
    res = resultants(channels, plate(), axis=0)
    assert float(res.my) == pytest.approx(AZ0 * fx)
    assert (float(res.ax), float(res.ay)) == pytest.approx((0.0, 0.0), abs=1e-12)


def test_free_moment_from_opposite_shears():
    res = resultants(channel_vector(fx12=-10.0, fx34=10.0), plate(), axis=0)
    assert float(res.mz) == pytest.approx(2 * B * 10.0)
    assert float(res.fx) == 0.0


def rigid_plate_channels(fx, fy, fz, x, y, free_moment=0.0, a=A, b=B, az0=AZ0):
    """Channels of a rigid plate loaded at (x, y) on its surface, by static equilibrium alone.

    Independent of the module under test: bilinear shares of the vertical load, the shear's
    moment about the sensor plane carried by the vertical sensors, and the vertical moment
    carried by the shear sensors.
    """
    share = 4 * a * b
    fz1 = fz * (a + x) * (b + y) / share
    fz2 = fz * (a - x) * (b + y) / share
    fz3 = fz * (a - x) * (b - y) / share
    fz4 = fz * (a + x) * (b - y) / share
    dy = az0 * fx / (4 * a)  # My = az0*Fx about the sensor plane
    dx = -az0 * fy / (4 * b)  # Mx = -az0*Fy
    mz = x * fy - y * fx + free_moment
    return channel_vector(
        fx12=fx / 2 - mz / (4 * b),
        fx34=fx / 2 + mz / (4 * b),
        fy14=fy / 2 + mz / (4 * a),
        fy23=fy / 2 - mz / (4 * a),
        fz1=fz1 - dy + dx,
        fz2=fz2 + dy + dx,
        fz3=fz3 + dy - dx,
        fz4=fz4 - dy - dx,
    )


@pytest.mark.parametrize("axis", ["+x", "-x", "+y", "-y"])
def test_known_static_load_for_every_mounting(axis):
    """A foot 5 cm ahead of the centre pushes the plate back by 40 N and down by 700 N."""
    geometry = plate(axis)
    # Walking-direction unit vector in plate coordinates.
    ux, uy = {"+x": (1, 0), "-x": (-1, 0), "+y": (0, 1), "-y": (0, -1)}[axis]
    channels = rigid_plate_channels(-40.0 * ux, -40.0 * uy, 700.0, 0.05 * ux, 0.05 * uy)
    load = sagittal_load(resultants(channels, geometry, axis=0), axis)
    # The plate pushes the foot forwards (+40 N anterior) and up (+700 N).
    assert float(load.grf_z) == pytest.approx(700.0)
    assert float(load.grf_x) == pytest.approx(40.0)
    assert float(load.cop_x) == pytest.approx(0.05)
    # The inverse map reproduces a load that statics alone determine up to the null space.
    again = channels_from_load(
        [-40.0 * ux, -40.0 * uy, 700.0], [0.05 * ux, 0.05 * uy], geometry, axis=0
    )
    np.testing.assert_allclose(geometry.matrix() @ again, geometry.matrix() @ channels, atol=1e-9)


loads = st.tuples(
    st.floats(-300, 300),
    st.floats(-300, 300),
    st.floats(20, 2000),
    st.floats(-0.25, 0.25),
    st.floats(-0.15, 0.15),
    st.floats(-20, 20),
)


@settings(max_examples=200, deadline=None)
@given(load=loads)
def test_random_loads_round_trip(load):
    fx, fy, fz, x, y, tz = load
    g = plate()
    c = channels_from_load([fx, fy, fz], [x, y], g, free_moment_nm=tz, axis=0)
    res = resultants(c, g, axis=0)
    np.testing.assert_allclose([res.fx, res.fy, res.fz], [fx, fy, fz], atol=1e-9)
    np.testing.assert_allclose([res.ax, res.ay], [x, y], atol=1e-9)
    np.testing.assert_allclose(res.mz, x * fy - y * fx + tz, atol=1e-8)


shear = st.floats(-300, 300)
vertical = st.floats(20, 500)


@settings(max_examples=100, deadline=None)
@given(
    channels=st.tuples(shear, shear, shear, shear, vertical, vertical, vertical, vertical).map(
        np.array
    )
)
def test_inverse_returns_the_minimum_norm_channels_of_the_same_load(channels):
    """Channels -> load -> channels gives the projection of the input onto the load space."""
    g = plate()
    res = resultants(channels, g, axis=0)
    free_moment = res.mz - res.ax * res.fy + res.ay * res.fx  # Kistler's Tz
    again = channels_from_load(
        [res.fx, res.fy, res.fz], [res.ax, res.ay], g, free_moment_nm=free_moment, axis=0
    )
    matrix = g.matrix()
    np.testing.assert_allclose(matrix @ again, matrix @ channels, atol=1e-7)
    np.testing.assert_allclose(again, np.linalg.pinv(matrix) @ matrix @ channels, atol=1e-7)
    assert np.linalg.norm(again) <= np.linalg.norm(channels) + 1e-9


def test_vectorised_over_trials_and_samples():
    rng = np.random.default_rng(0)
    g = plate()
    force = rng.normal(0, 50, (4, 3, 100)) + np.array([0, 0, 800])[:, None]
    cop = rng.uniform(-0.1, 0.1, (4, 2, 100))
    res = resultants(channels_from_load(force, cop, g), g)
    assert res.ax.shape == (4, 100)
    np.testing.assert_allclose(res.ax, cop[:, 0], atol=1e-9)
    np.testing.assert_allclose(res.fz, force[:, 2], atol=1e-9)


def test_unloaded_plate_has_no_cop():
    res = resultants(np.zeros(8), plate(), axis=0)
    assert np.isnan(res.ax) and np.isnan(res.ay)


def test_wrong_channel_count_is_rejected():
    with pytest.raises(ValueError, match="expected 8 channels"):
        resultants(np.zeros((7, 10)), plate())


def test_ankle_torque_zeroes_cop_at_heel_contact():
    cop = np.array([[0.10, 0.12, 0.15], [0.20, 0.21, 0.30]])
    load = SagittalLoad(grf_x=np.full((2, 3), 10.0), grf_z=np.full((2, 3), 500.0), cop_x=cop)
    torque, dx = ankle_torque(load, [0, 1], heel_to_ankle_m=0.04, ankle_height_m=0.08)
    expected_dx = np.array([[-0.04, -0.02, 0.01], [-0.05, -0.04, 0.05]])
    np.testing.assert_allclose(dx, expected_dx, atol=1e-12)
    np.testing.assert_allclose(torque, 500.0 * expected_dx + 10.0 * 0.08)


def test_ankle_torque_sign_is_dorsiflexing():
    # Forefoot loading (COP ahead of the ankle) pushes the toes up: positive torque.
    load = SagittalLoad(np.zeros(2), np.full(2, 700.0), np.array([0.0, 0.15]))
    torque, _ = ankle_torque(load, 0, heel_to_ankle_m=0.05, ankle_height_m=0.08)
    assert torque[1] > 0 > torque[0]


def test_ankle_torque_rejects_heel_contact_outside_the_trial():
    load = SagittalLoad(np.zeros(3), np.ones(3), np.zeros(3))
    with pytest.raises(EventNotFoundError, match="outside the trial"):
        ankle_torque(load, 5, heel_to_ankle_m=0.0, ankle_height_m=0.08)


def test_plate_geometry_is_validated():
    with pytest.raises(ValueError, match="az0_m"):
        PlateGeometry(a_m=0.1, b_m=0.1, az0_m=0.05)


# --- plate types ----------------------------------------------------------------------------------

DIRECTIONS = {"+x": (1, 0), "-x": (-1, 0), "+y": (0, 1), "-y": (0, -1)}


def walking_load(axis):
    """A foot 5 cm ahead of and 2 cm left of the centre, pushed forwards by 40 N, to the right
    by 15 N and up by 700 N, as the load on the plate (plate frame, z down) and its point."""
    ux, uy = DIRECTIONS[axis]
    lx, ly = -uy, ux  # the plate-frame direction of the walker's right (z down: y = right)
    # walking-frame vectors (x fwd, y left) -> plate frame: fwd = u, left = -right
    fwd = np.array([ux, uy])
    left = -np.array([lx, ly])
    grf_h = 40.0 * fwd - 15.0 * left  # GRF (plate on foot): forwards, to the right
    force = [-grf_h[0], -grf_h[1], 700.0]  # load on plate: opposite, z down
    cop = 0.05 * fwd + 0.02 * left
    return force, cop


@pytest.mark.parametrize("axis", ["+x", "-x", "+y", "-y"])
@pytest.mark.parametrize("kind", ["kistler8", "six_axis"])
def test_linear_plates_give_the_walking_frame_load(kind, axis):
    geometry = plate(axis) if kind == "kistler8" else SixAxisPlate(az0_m=AZ0, anterior_axis=axis)
    force, cop = walking_load(axis)
    channels = channels_from_load(force, cop, geometry, free_moment_nm=-3.0, axis=0)
    lab = geometry.lab_load(channels, axis=0)
    assert [float(v) for v in (lab.grf_x, lab.grf_y, lab.grf_z)] == pytest.approx(
        [40.0, -15.0, 700.0]
    )
    assert [float(lab.cop_x), float(lab.cop_y)] == pytest.approx([0.05, 0.02])
    # the foot twists the plate by 3 N·m about the upward vertical (-3 about plate z, which
    # points down); the plate's free moment on the foot is the reaction: -3 N·m about up
    assert float(lab.free_moment) == pytest.approx(-3.0)
    sagittal = geometry.sagittal_matrix() @ geometry.load_signals(channels, axis=0)
    assert sagittal == pytest.approx([40.0, 700.0, 700.0 * 0.05])


@pytest.mark.parametrize("axis", ["+x", "-x", "+y", "-y"])
def test_grf_cop_plate_turns_the_lab_frame_into_the_walking_frame(axis):
    ux, uy = DIRECTIONS[axis]
    # lab frame z up: the walker's left is (-uy, ux)
    grf = 40.0 * np.array([ux, uy]) - 15.0 * np.array([-uy, ux])
    cop = 0.30 * np.array([ux, uy]) + 0.02 * np.array([-uy, ux])
    g = GrfCopPlate(anterior_axis=axis)
    data = np.array([grf[0], grf[1], 700.0, cop[0], cop[1]])
    lab = g.lab_load(data, axis=0)
    assert [float(v) for v in (lab.grf_x, lab.grf_y, lab.grf_z)] == pytest.approx(
        [40.0, -15.0, 700.0]
    )
    assert [float(lab.cop_x), float(lab.cop_y)] == pytest.approx([0.30, 0.02])
    assert np.isnan(lab.free_moment)
    assert g.load_signals(data, axis=0) == pytest.approx([40.0, 700.0, 700.0 * 0.30])
    np.testing.assert_array_equal(g.sagittal_matrix(), np.eye(3))


def test_grf_cop_moment_is_zero_where_the_cop_is_empty():
    data = np.array([[0.0, 5.0], [0.0, 0.0], [0.5, 700.0], [np.nan, 0.1], [np.nan, 0.0]])
    signals = GrfCopPlate().load_signals(data)
    np.testing.assert_allclose(signals, [[0.0, 5.0], [0.5, 700.0], [0.0, 70.0]])


def test_six_axis_resultants_of_a_kistler_plate_give_the_same_sagittal_signals():
    rng = np.random.default_rng(1)
    kistler = plate("-y")
    channels = rng.normal(0, 50, (8, 20)) + np.array([0, 0, 0, 0, 200, 200, 200, 200])[:, None]
    res = resultants(channels, kistler)
    six = np.stack([res.fx, res.fy, res.fz, res.mx, res.my, res.mz])
    six_axis = SixAxisPlate(az0_m=AZ0, anterior_axis="-y")
    np.testing.assert_allclose(
        six_axis.sagittal_matrix() @ six, kistler.sagittal_matrix() @ channels, atol=1e-9
    )


def test_plate_types_are_named_and_checked():
    assert PLATE_TYPES == ("kistler8", "six_axis", "grf_cop")
    assert plate_class("six_axis") is SixAxisPlate
    with pytest.raises(ValueError, match="type: expected one of kistler8, six_axis, grf_cop"):
        plate_class("amti")
    with pytest.raises(ValueError, match=r"expected 6 channels .* six_axis"):
        resultants(np.zeros(8), SixAxisPlate(az0_m=0.0), axis=0)
    with pytest.raises(ValueError, match="az0_m"):
        SixAxisPlate(az0_m=0.01)
