"""The new physics of the dynamics: roll-off, lumped heating, engagement and impact."""

from __future__ import annotations

import numpy as np
import pytest

from ecdsim.physics import mechanics, rolloff, thermal

SHAPES = [(), (3,), (2, 3)]


def _filled(shape: tuple[int, ...], value: float) -> np.ndarray:
    return np.full(shape, value)


@pytest.mark.parametrize("shape", SHAPES)
def test_kloss_torque_slope_peak_and_tail(shape: tuple[int, ...]) -> None:
    bd, peak_speed = 1.3e-4, 2000.0
    peak_torque = rolloff.peak_torque_from_damping(_filled(shape, bd), peak_speed)
    # Hand: T_peak = BD * omega_peak / 2 = 0.13 N*m.
    assert np.allclose(peak_torque, 0.13, rtol=1e-15, atol=0.0)
    assert np.shape(peak_torque) == shape
    # At the peak speed the torque is T_peak (x = 1: 2x/(1+x^2) = 1).
    at_peak = rolloff.kloss_torque(_filled(shape, peak_speed), peak_torque, peak_speed)
    assert np.allclose(at_peak, 0.13, rtol=1e-15, atol=0.0)
    # Far beyond the peak it falls as 2 T_peak omega_peak / omega: x = 100 -> 200/10001.
    tail = rolloff.kloss_torque(_filled(shape, 100 * peak_speed), peak_torque, peak_speed)
    assert np.allclose(tail, 0.13 * 200.0 / 10001.0, rtol=1e-14, atol=0.0)
    # The slope at zero is BD (the linear range of paper section 2.1).
    slope0 = rolloff.kloss_speed_derivative(_filled(shape, 0.0), peak_torque, peak_speed)
    assert np.allclose(slope0, bd, rtol=1e-15, atol=0.0)


def test_kloss_derivatives_match_finite_differences() -> None:
    speed = np.array([0.0, 150.0, 2000.0, 5000.0])
    peak_torque, peak_speed = 0.13, 2000.0
    h = 1e-3
    numeric = (
        rolloff.kloss_torque(speed + h, peak_torque, peak_speed)
        - rolloff.kloss_torque(speed - h, peak_torque, peak_speed)
    ) / (2 * h)
    analytic = rolloff.kloss_speed_derivative(speed, peak_torque, peak_speed)
    # Central differences with h = 1e-3 on a curve of scale 2000 rad/s: error ~ h^2 T''' ~ 1e-13.
    assert np.allclose(analytic, numeric, rtol=1e-7, atol=1e-12)
    numeric_peak = (
        rolloff.kloss_torque(speed, peak_torque, peak_speed + h)
        - rolloff.kloss_torque(speed, peak_torque, peak_speed - h)
    ) / (2 * h)
    analytic_peak = rolloff.kloss_peak_speed_derivative(speed, peak_torque, peak_speed)
    assert np.allclose(analytic_peak, numeric_peak, rtol=1e-7, atol=1e-12)


@pytest.mark.parametrize("shape", SHAPES)
def test_peak_speed_follows_resistivity(shape: tuple[int, ...]) -> None:
    temps = _filled(shape, -40.0)
    peak = rolloff.peak_speed_at(temps, 2000.0, 0.0039, 25.0)
    # Hand: 2000 * (1 + 0.0039 * (-65)) = 1493.
    assert np.allclose(peak, 1493.0, rtol=1e-14, atol=0.0)
    assert np.shape(peak) == shape


@pytest.mark.parametrize("shape", SHAPES)
def test_lumped_heating(shape: tuple[int, ...]) -> None:
    power = _filled(shape, 10.0)
    # Adiabatic: dT/dt = P / C = 10 / 4 = 2.5 K/s whatever the temperature.
    rate = thermal.temperature_rate(power, 80.0, 25.0, 4.0, np.inf)
    assert np.allclose(rate, 2.5, rtol=1e-15, atol=0.0)
    assert np.shape(rate) == shape
    # With R = 5 K/W at 35 degC over 25 degC ambient: (10 - 10/5) / 4 = 2 K/s.
    cooled = thermal.temperature_rate(power, 35.0, 25.0, 4.0, 5.0)
    assert np.allclose(cooled, 2.0, rtol=1e-15, atol=0.0)
    assert np.allclose(thermal.adiabatic_temperature_rise(power, 4.0), 2.5, rtol=1e-15, atol=0.0)


@pytest.mark.parametrize("shape", SHAPES)
def test_engagement_conserves_momentum(shape: tuple[int, ...]) -> None:
    load_inertia, damper_inertia = _filled(shape, 3.0), 1.0
    speed = 2.0
    after, loss = mechanics.plastic_engagement(load_inertia, speed, damper_inertia)
    # Momentum: 3 * 2 = (3 + 1) * 1.5; energy: 0.5*3*4 - 0.5*4*1.5^2 = 6 - 4.5 = 1.5 J.
    assert np.allclose(after, 1.5, rtol=1e-15, atol=0.0)
    assert np.allclose(loss, 1.5, rtol=1e-15, atol=0.0)
    assert np.shape(after) == shape


@pytest.mark.parametrize("shape", SHAPES)
def test_rebound_and_kinetic_energy(shape: tuple[int, ...]) -> None:
    after, loss = mechanics.rebound(_filled(shape, 0.4), 0.5, 5.0)
    # Newton's law: -e * v = -0.2; loss (1 - e^2) J v^2 / 2 = 0.75 * 0.4 = 0.3 J.
    assert np.allclose(after, -0.2, rtol=1e-15, atol=0.0)
    assert np.allclose(loss, 0.3, rtol=1e-14, atol=0.0)
    # 0.5 * 5 * 0.16 = 0.4 J; one or two roundings.
    assert np.allclose(mechanics.kinetic_energy(5.0, _filled(shape, 0.4)), 0.4, rtol=1e-15, atol=0)
    # A rotor of 2e-7 kg*m^2 behind 380:1 weighs 2e-7 * 144400 = 0.02888 kg*m^2 at the input.
    reflected = mechanics.reflect_inertia_to_input(_filled(shape, 2e-7), 380.0)
    assert np.allclose(reflected, 0.02888, rtol=1e-14, atol=0.0)  # two roundings of 2e-7
    assert np.allclose(mechanics.static_friction(_filled(shape, 2.0), 1.25), 2.5, rtol=0, atol=0)
