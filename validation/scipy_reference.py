"""Tight scipy integrations of the validation cases' equations, written from their sources.

Nothing here imports ecdsim: each right-hand side is typed from the equations of the source
it names (the Modelica models' equations, the paper's Eq. 1-11, the lumped heat balance), in
plain floats, and integrated with scipy at tolerances far below the ones the validation
allows (rtol 1e-12). They serve two purposes: a second, tight reference for ecdsim, and a
check that a case is mapped onto the right equations (the Modelica reference results must
agree with them too, to their own solver's tolerance).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.integrate import solve_ivp

FloatArray = npt.NDArray[np.float64]
Rhs = Callable[[float, FloatArray], list[float]]

RTOL = 1e-12  # far below every validation tolerance
ATOL = 1e-14


@dataclass(frozen=True)
class SpinDown:
    """A free inertia braked by a temperature-dependent Kloss torque, heating a capacity.

    The equations of Modelica.Mechanics.Rotational.Sources.EddyCurrentTorque with an
    Inertia and an isolated HeatCapacitor (MSL Rotational.Examples.EddyCurrentBrake):

        J w' = -tau,  C T' = tau w,  phi' = w,
        tau = 2 tau_n x / (1 + x^2),  x = w / (w_n (1 + alpha (T - T_ref))).

    Attributes
    ----------
    inertia : J [kg*m^2]
    tau_nominal : tau_n, the peak torque [N*m]
    w_nominal : w_n, the speed of peak torque at T_ref [rad/s]
    alpha : temperature coefficient of w_n [1/K]
    reference_temperature : T_ref [degC]
    heat_capacity : C [J/K]
    """

    inertia: float
    tau_nominal: float
    w_nominal: float
    alpha: float
    reference_temperature: float
    heat_capacity: float

    def torque(self, speed: float, temperature: float) -> float:
        """The braking torque at speed w [rad/s] and brake temperature T [degC] [N*m]."""
        x = speed / (
            self.w_nominal * (1.0 + self.alpha * (temperature - self.reference_temperature))
        )
        return 2.0 * self.tau_nominal * x / (1.0 + x * x)

    def solve(self, speed0: float, temperature0: float, times: FloatArray) -> dict[str, FloatArray]:
        """Angle [rad], speed [rad/s], temperature [degC], loss power [W] at ``times`` [s]."""

        def rhs(_t: float, y: FloatArray) -> list[float]:
            _phi, w, temp = y
            tau = self.torque(w, temp)
            return [w, -tau / self.inertia, tau * w / self.heat_capacity]

        sol = solve_ivp(
            rhs,
            (0.0, float(times[-1])),
            [0.0, speed0, temperature0],
            method="Radau",
            t_eval=times,
            rtol=RTOL,
            atol=ATOL,
        )
        angle, speed, temperature = sol.y
        power = np.array([self.torque(w, t) * w for w, t in zip(speed, temperature, strict=True)])
        return {"angle": angle, "speed": speed, "temperature": temperature, "power": power}


def damped_mass(
    mass: float, damping: float, stiffness: float, speed0: float, times: FloatArray
) -> dict[str, FloatArray]:
    """``m x'' = -d x' - c x`` from x = 0, x' = v0: position [m] and speed [m/s] at ``times``.

    The mass-damper(-spring) of MSL Translational.Examples.Damper.
    """

    def rhs(_t: float, y: FloatArray) -> list[float]:
        x, v = y
        return [v, (-damping * v - stiffness * x) / mass]

    sol = solve_ivp(
        rhs,
        (0.0, float(times[-1])),
        [0.0, speed0],
        method="DOP853",
        t_eval=times,
        rtol=RTOL,
        atol=ATOL,
    )
    return {"position": sol.y[0], "speed": sol.y[1]}


@dataclass(frozen=True)
class PaperSystem:
    """The paper's section 6 Cc-16 system, evaluated from its printed constants.

    Eq. 1-4 at the analysis temperature T [degC]; the spring is Eq. 7 (linear in angle); FS_T
    is the paper's linear system friction. Values are the paper's, typed here.
    """

    bd: float = 1.3e-4  # BD [N*m*s/rad], rated at +25 degC
    bd_coefficient: float = -0.004  # Eq. 1 [1/K]
    bg_fraction: float = 0.26  # BG = 0.26 BD
    fd: float = 7.9e-4  # FD [N*m]
    fl_slope: float = -2.12e-6  # FL_T = slope T + at_0 [N*m/K]
    fl_at_0: float = 2.2e-4
    fg: float = 4.5e-4  # FG [N*m]
    ratio: float = 380.0  # N
    start_torque: float = 3.73  # Ts [N*m]
    end_torque: float = 1.58  # Te [N*m]
    travel: float = 1.57  # delta theta [rad]
    fs_slope: float = -0.0044  # FS_T = slope T + at_0 [N*m/K]
    fs_at_0: float = 0.58

    def damper_rate(self, temperature: float) -> float:
        """BD_T, the eddy-current part of Eq. 1 [N*m*s/rad]."""
        return self.bd * (1.0 + self.bd_coefficient * (temperature - 25.0))

    def becd(self, temperature: float) -> float:
        """BECD_T = (BD_T + BG) N^2 (Eq. 1, 3) [N*m*s/rad]."""
        return (self.damper_rate(temperature) + self.bg_fraction * self.bd) * self.ratio**2

    def fecd(self, temperature: float) -> float:
        """FECD_T = (FD + FL_T + FG) N (Eq. 2, 4) [N*m]."""
        fl = self.fl_slope * temperature + self.fl_at_0
        return (self.fd + fl + self.fg) * self.ratio

    def friction(self, temperature: float) -> float:
        """FECD_T + FS_T [N*m]."""
        return self.fecd(temperature) + self.fs_slope * temperature + self.fs_at_0

    def spring(self, angle: float) -> float:
        """Eq. 7: Ts at release, Te at the end of travel, linear in the deployed angle."""
        return self.start_torque + (self.end_torque - self.start_torque) * angle / self.travel

    def paper_time(self, temperature: float) -> float:
        """Eq. 8-11 as printed: travel over the mean of the start and end speeds [s]."""
        b, f = self.becd(temperature), self.friction(temperature)
        start = (self.start_torque - f) / b
        end = (self.end_torque - f) / b
        return self.travel / ((start + end) / 2.0)

    def quasi_static_time(self, temperature: float) -> float:
        """Time to travel by integrating Eq. 5 along the travel, phi' = (T(phi) - F) / B [s]."""
        b, f = self.becd(temperature), self.friction(temperature)
        return _arrival(lambda _t, y: [(self.spring(y[0]) - f) / b], [0.0], self.travel, "DOP853")[
            0
        ]

    def dynamic_time(self, temperature: float, inertia: float) -> tuple[float, float]:
        """Deployment time [s] and arrival speed [rad/s] with inertia J [kg*m^2] from rest.

        ``J w' = T(phi) - F - B w`` (the spring beats the friction at release, so the
        mechanism breaks away at once and never stops before the end).
        """
        b, f = self.becd(temperature), self.friction(temperature)

        def rhs(_t: float, y: FloatArray) -> list[float]:
            phi, w = y
            return [w, (self.spring(phi) - f - b * w) / inertia]

        time, state = _arrival(rhs, [0.0, 0.0], self.travel, "Radau")
        return time, float(state[1])

    def heated_time(
        self, temperature: float, inertia: float, heat_capacity: float, resistance: float
    ) -> tuple[float, float, float]:
        """Time [s], arrival speed [rad/s], damper temperature at arrival [degC] with heating.

        The damper's temperature T_d follows ``C T_d' = BD(T_d) (N w)^2 - (T_d - T) / R``
        (only the eddy-current power heats it) and its damping follows Eq. 1 at T_d; the
        gearbox damping and every friction stay at the ambient temperature T.
        """
        f = self.friction(temperature)
        bg = self.bg_fraction * self.bd * self.ratio**2

        def rhs(_t: float, y: FloatArray) -> list[float]:
            phi, w, td = y
            eddy = self.damper_rate(td) * self.ratio**2
            power = eddy * w * w
            return [
                w,
                (self.spring(phi) - f - (eddy + bg) * w) / inertia,
                (power - (td - temperature) / resistance) / heat_capacity,
            ]

        time, state = _arrival(rhs, [0.0, 0.0, temperature], self.travel, "Radau")
        return time, float(state[1]), float(state[2])

    def stribeck_time(
        self, temperature: float, inertia: float, static_factor: float, stribeck_speed: float
    ) -> tuple[float, float, float]:
        """Time [s], arrival speed [rad/s] and speed-dependent dissipation [J] with Stribeck
        friction, from rest.

        ``J w' = T(phi) - F - (f - 1) F exp(-(w / w_St)^2) - B w``: the friction falls from
        the breakaway f F at rest to the kinetic F = FECD_T + FS_T (the LuGre model's
        Stribeck curve, Canudas de Wit et al. 1995), one factor f for both frictions. The
        dissipation is that of B and of the excess over F,
        ``int (B w + (f - 1) F exp(...)) w dt``.
        """
        b, f = self.becd(temperature), self.friction(temperature)
        excess = (static_factor - 1.0) * f

        def rhs(_t: float, y: FloatArray) -> list[float]:
            phi, w, _ = y
            extra = excess * math.exp(-((w / stribeck_speed) ** 2))
            return [w, (self.spring(phi) - f - extra - b * w) / inertia, (b * w + extra) * w]

        time, state = _arrival(rhs, [0.0, 0.0, 0.0], self.travel, "Radau")
        return time, float(state[1]), float(state[2])

    def compliant_time(
        self,
        temperature: float,
        load_inertia: float,
        damper_inertia: float,
        stiffness: float,
        damping: float,
        lost_motion: float,
        until: float = math.inf,
    ) -> tuple[float, float, float, float]:
        """Engagement time [s], deployment time [s], arrival speed [rad/s] and the mesh's
        dissipation [J] with a compliant mesh behind the lost motion, from rest; with
        ``until`` [s] before the arrival, the time and speed are nan and the dissipation is
        that up to ``until``.

        Two bodies (the MSL's ElastoBacklash2 between them, docs/model.md): the load
        ``J_L w_L' = T(phi_L) - FS_T - tau`` and the damper side
        ``J_D w_D' = tau - FECD_T - BECD_T w_D``, ``tau = c (delta - b/2) + d delta'`` past
        the flank, with ``delta = phi_L - phi_D``. Three phases for the paper's system: the
        load alone across the gap; the mesh pressing while the damper side is held by its
        friction (until ``tau`` reaches FECD_T); both moving to the end. Each phase's end is a
        terminal event; the damper side stopping or the contact opening would stop the
        reference (they do not occur here: its eddy damping is too strong to bounce).
        """
        fs = self.fs_slope * temperature + self.fs_at_0
        fecd, becd = self.fecd(temperature), self.becd(temperature)
        half = 0.5 * lost_motion
        jl, jd, c, d = load_inertia, damper_inertia, stiffness, damping

        def tau(y: FloatArray) -> float:
            return float(c * (y[2] - half) + d * (y[1] - y[3]))

        def rhs(phase: int) -> Rhs:
            def f(_t: float, y: FloatArray) -> list[float]:
                torque = tau(y) if phase > 0 else 0.0
                load = (self.spring(float(y[0])) - fs - torque) / jl
                damper = (torque - fecd - becd * y[3]) / jd if phase == 2 else 0.0
                w_rel = float(y[1] - y[3])
                return [float(y[1]), load, w_rel, damper, d * w_rel * w_rel if phase else 0.0]

            return f

        def event(func: Callable[[float, FloatArray], float], direction: float) -> Any:
            func.terminal = True  # type: ignore[attr-defined]
            func.direction = direction  # type: ignore[attr-defined]
            return func

        arrive = event(lambda _t, y: float(y[0] - self.travel), 1.0)
        closing = event(lambda _t, y: float(y[2] - half), 1.0)
        breakaway = event(lambda _t, y: tau(y) - fecd, 1.0)
        stopping = event(lambda _t, y: float(y[3]), -1.0)
        opening = event(lambda _t, y: tau(y), -1.0)
        y = np.array([0.0, 0.0, -half, 0.0, 0.0])
        t = 0.0
        engage = math.nan
        phases = (
            (0, [arrive, closing]),
            (1, [arrive, breakaway, opening]),
            (2, [arrive, stopping, opening]),
        )
        for phase, events in phases:
            sol = solve_ivp(
                rhs(phase),
                (t, min(t + 1e4, until)),
                y,
                method="Radau",
                events=events,
                rtol=RTOL,
                atol=ATOL,
            )
            if sol.status == 0 and until < math.inf:
                return engage, math.nan, math.nan, float(sol.y[4, -1])
            hit = [i for i, times in enumerate(sol.t_events) if len(times)]
            assert sol.status == 1, "the reference did not reach an event"
            assert hit[0] in (0, 1), "the damper side stopped or the contact opened"
            t, y = float(sol.t_events[hit[0]][0]), np.asarray(sol.y_events[hit[0]][0], float)
            if phase == 0:
                engage = t
            if hit[0] == 0:
                return engage, t, float(y[1]), float(y[4])
        raise AssertionError("the reference did not arrive")


def _arrival(rhs: Rhs, y0: list[float], travel: float, method: str) -> tuple[float, FloatArray]:
    """Integrate from rest-or-given state until ``y[0]`` reaches the travel: (time, state)."""

    def arrive(_t: float, y: FloatArray) -> float:
        return float(y[0] - travel)

    arrive.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0.0, 1e4), y0, method=method, events=arrive, rtol=RTOL, atol=ATOL)
    return float(sol.t_events[0][0]), np.asarray(sol.y_events[0][0], dtype=float)


# The resistive torque of validation case "resistive_table" (harness and blanket torque
# against angle, N*m; a negative row assists), rows [angle rad, torque N*m].
RESISTIVE_ROWS: tuple[tuple[float, float], ...] = (
    (0.0, 0.2),
    (0.5, 0.6),
    (0.9, -0.1),
    (1.3, 0.3),
    (2.0, 0.0),
)


@dataclass(frozen=True)
class ResistedPaperSystem(PaperSystem):
    """The paper's system with the spring lowered by :data:`RESISTIVE_ROWS`, linear between."""

    def spring(self, angle: float) -> float:
        """Eq. 7 less the resistive torque interpolated in the rows."""
        angles = [a for a, _ in RESISTIVE_ROWS]
        torques = [r for _, r in RESISTIVE_ROWS]
        return super().spring(angle) - float(np.interp(angle, angles, torques))


# The ground test of validation case "gravity_ground_test" (ILLUSTRATIVE values): the
# deployed mass [kg], its CG radius from the hinge [m], the release angle from the
# downward vertical [rad] and the offloaded fraction of the weight [-].
GRAVITY = {"mass": 1.2, "cg_radius": 0.3, "release_angle": -math.pi / 3, "offload": 0.9}
STANDARD_GRAVITY = 9.80665  # m/s^2 (CGPM 1901), typed here on its own


@dataclass(frozen=True)
class GroundTestPaperSystem(PaperSystem):
    """The paper's system in a 1 g ground test: Eq. 7 less m g r (1 - offload) sin(theta_0 + phi)
    (rigid-body statics: the weight's moment about the hinge, opposing deployment positive)."""

    def gravity(self, angle: float) -> float:
        """The gravity torque about the hinge [N*m], opposing deployment positive."""
        g = GRAVITY
        weight = g["mass"] * STANDARD_GRAVITY * g["cg_radius"] * (1.0 - g["offload"])
        return weight * math.sin(g["release_angle"] + angle)

    def spring(self, angle: float) -> float:
        """Eq. 7 less the gravity torque."""
        return super().spring(angle) - self.gravity(angle)

    def paper_time(self, temperature: float) -> float:
        """Eq. 8-11 with the end-point torques less gravity there [s]."""
        b, f = self.becd(temperature), self.friction(temperature)
        start = (self.spring(0.0) - f) / b
        end = (self.spring(self.travel) - f) / b
        return self.travel / ((start + end) / 2.0)


# Two-node heating of validation case "two_node_heating" (issue 16 item 6): rotor C_r
# [J/K], rotor to housing R_rh [K/W], housing C_h [J/K], housing to mount R_he [K/W].
# ILLUSTRATIVE values, light enough for the rotor to warm by kelvins in one deployment.
TWO_NODE = {"c_r": 0.05, "r_rh": 20.0, "c_h": 0.5, "r_he": 100.0}


def two_node_time(
    system: PaperSystem,
    temperature: float,
    inertia: float,
    start: tuple[float, float] = (0.0, 0.0),
) -> tuple[float, float, float]:
    """Time [s], rotor and housing temperatures at arrival [degC] with two-node heating.

    ``C_r T_r' = BD(T_r) (N w)^2 - (T_r - T_h) / R_rh`` and
    ``C_h T_h' = (T_r - T_h) / R_rh - (T_h - T) / R_he`` (two lumped capacitances,
    Incropera et al., Fundamentals of Heat and Mass Transfer, sections 3.1.3 and 5.2);
    the damping follows Eq. 1 at T_r, BG and the frictions stay at T. ``start``: the
    rotor's and housing's rises above T at release [K].
    """
    c_r, r_rh, c_h, r_he = (TWO_NODE[k] for k in ("c_r", "r_rh", "c_h", "r_he"))
    f = system.friction(temperature)
    bg = system.bg_fraction * system.bd * system.ratio**2

    def rhs(_t: float, y: FloatArray) -> list[float]:
        phi, w, tr, th = y
        eddy = system.damper_rate(tr) * system.ratio**2
        flow = (tr - th) / r_rh
        return [
            w,
            (system.spring(phi) - f - (eddy + bg) * w) / inertia,
            (eddy * w * w - flow) / c_r,
            (flow - (th - temperature) / r_he) / c_h,
        ]

    y0 = [0.0, 0.0, temperature + start[0], temperature + start[1]]
    time, state = _arrival(rhs, y0, system.travel, "Radau")
    return time, float(state[2]), float(state[3])


def two_node_relaxed(rotor: float, housing: float, time: float) -> tuple[float, float]:
    """The rises [K] after ``time`` [s] without heat input: scipy's matrix exponential of
    ``[[-1/(R_rh C_r), 1/(R_rh C_r)], [1/(R_rh C_h), -(1/R_rh + 1/R_he)/C_h]]``."""
    from scipy.linalg import expm

    c_r, r_rh, c_h, r_he = (TWO_NODE[k] for k in ("c_r", "r_rh", "c_h", "r_he"))
    a = np.array(
        [
            [-1.0 / (r_rh * c_r), 1.0 / (r_rh * c_r)],
            [1.0 / (r_rh * c_h), -(1.0 / r_rh + 1.0 / r_he) / c_h],
        ]
    )
    out = expm(a * time) @ np.array([rotor, housing])
    return float(out[0]), float(out[1])


# Validation case "lossy_gear" (issue 16 item 5): a load braked by a rising resistance
# (ILLUSTRATIVE rows, rad and N*m) behind a lossy mesh and a heavy rotor.
LOSSY_ROWS: tuple[tuple[float, float], ...] = ((0.0, 0.0), (0.3, 0.0), (0.6, 5.0), (1.6, 5.0))


def _crossing(row: float) -> Callable[[float, FloatArray], float]:
    """A terminal event: the angle passes a table row."""

    def event(_s: float, y: FloatArray) -> float:
        return float(y[0]) - row

    return event


@dataclass(frozen=True)
class LossyGearTrain:
    """The paper's spring and frictions driving a damper through a lossy mesh (LossyGear).

    The equations of Modelica.Mechanics.Rotational.Components.LossyGear without bearing
    friction, between the load J_L (with the spring, the table and FS_T) and the damper side
    J_D (rotor at the fast shaft times N^2, needing D = B_q w + F_q sign(w) through an ideal
    gear). M the mesh torque N tau_out; forward (M w >= 0) the load supplies M / eta_f,
    back-driven M eta_b:

        J_L w' = A - m M,  J_D w' = M - D   =>  w' = (A - m D) / (J_L + m J_D),

    m = 1/eta_f or eta_b, the mode that of the sign of (J_L D + J_D A) w. Integrated piece
    by piece between mode switches, zero speeds and table rows (terminal events).
    """

    damper_rate: float = 1.3e-5  # BD [N*m*s/rad]: a tenth of the paper's
    rotor: float = 1e-4  # [kg*m^2] at the fast shaft
    load_inertia: float = 5.0
    eta_f: float = 0.8
    eta_b: float = 0.6

    def run(self, temperature: float) -> dict[str, float]:
        """Until it sticks: first switch time, stick time [s] and angle [rad], gear loss [J]."""
        n = 380.0
        t = temperature
        bq = (self.damper_rate * (1.0 - 0.004 * (t - 25.0)) + 0.26 * self.damper_rate) * n**2
        fq = (7.9e-4 + (-2.12e-6 * t + 2.2e-4)) * n  # FD + FL_T, no FG
        fs = -0.0044 * t + 0.58
        j_l, j_d = self.load_inertia, self.rotor * n**2
        rows = [a for a, _ in LOSSY_ROWS]
        values = [r for _, r in LOSSY_ROWS]

        def net(phi: float) -> float:
            return 3.73 + (1.58 - 3.73) * phi / 1.57 - float(np.interp(phi, rows, values))

        state = np.array([0.0, 0.0, 0.0])
        time, sign, forward, switched = 0.0, 1.0, True, False
        switches: list[float] = []
        for _ in range(100):
            phi, w = float(state[0]), float(state[1])
            if w == 0.0:
                if abs(net(phi)) <= fs + fq / self.eta_f:
                    return {
                        "switch": switches[0] if switches else math.inf,
                        "stick_time": time,
                        "stick_angle": phi,
                        "gear_loss": float(state[2]),
                    }
                sign = math.copysign(1.0, net(phi))
            if not switched:
                forward = (j_l * (bq * w + fq * sign) + j_d * (net(phi) - fs * sign)) * sign >= 0
            switched = False
            m = 1.0 / self.eta_f if forward else self.eta_b

            def rhs(_s: float, y: FloatArray, m: float = m, sg: float = sign) -> list[float]:
                d = bq * y[1] + fq * sg
                acc = (net(float(y[0])) - fs * sg - m * d) / (j_l + m * j_d)
                return [float(y[1]), acc, (m - 1.0) * (d + j_d * acc) * float(y[1])]

            def stop(_s: float, y: FloatArray, sg: float = sign) -> float:
                return float(y[1]) * sg

            def flow(_s: float, y: FloatArray, sg: float = sign) -> float:
                d = bq * float(y[1]) + fq * sg
                return (j_l * d + j_d * (net(float(y[0])) - fs * sg)) * sg

            stop.direction = -1  # type: ignore[attr-defined]
            flow.direction = -1 if forward else 1  # type: ignore[attr-defined]
            events: list[Callable[[float, FloatArray], float]] = [stop, flow]
            for row in rows[1:-1]:
                if abs(row - phi) > 1e-12:
                    events.append(_crossing(row))
            for event in events:
                event.terminal = True  # type: ignore[attr-defined]
            sol = solve_ivp(
                rhs, (0.0, 1e3), state, method="DOP853", rtol=RTOL, atol=ATOL, events=events
            )
            k = min(
                (j for j, te in enumerate(sol.t_events) if len(te)),
                key=lambda j: float(sol.t_events[j][0]),
            )
            time += float(sol.t_events[k][0])
            state = np.array(sol.y_events[k][0], dtype=float)
            if k == 0:
                state[1] = 0.0
            elif k == 1:
                switches.append(time)
                forward, switched = not forward, True
        raise RuntimeError("the lossy gear train did not come to rest")
