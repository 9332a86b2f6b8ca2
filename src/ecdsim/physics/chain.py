"""Kinematics and Lagrangian terms of a planar open chain of rigid panels (a wing).

A wing is a chain of n rigid panels joined by revolute hinges whose axes are normal to
one plane: hinge 1 joins panel 1 to the fixed base (the spacecraft) at the origin,
hinge i joins panel i to panel i-1. Everything here follows the Euler-Lagrange
equations of an open chain (Spong, Hutchinson and Vidyasagar, *Robot Modeling and
Control*, Wiley 2006, chapter 7: the inertia matrix ``D(q) = sum_i m_i Jv_i^T Jv_i +
Jw_i^T I_i Jw_i`` of section 7.3, the Christoffel symbols of section 7.4 and the planar
elbow manipulator of section 7.4.2; Lynch and Park, *Modern Robotics*, 2017, section
8.1), written for a planar chain in closed form.

Conventions (docs/wing.md has a sketch):

- ``angles`` q are the *relative* hinge angles [rad]: q_1 is panel 1's angle from the
  base's x axis, q_i (i > 1) panel i's angle from panel i-1, counter-clockwise positive.
  Panel i's absolute angle is ``Theta_i = q_1 + ... + q_i``.
- Panel i runs from its inboard hinge (at ``p_i``) along its unit vector
  ``e_i = (cos Theta_i, sin Theta_i)`` to its outboard hinge ``p_{i+1} = p_i + L_i e_i``
  (``length`` L_i, hinge to hinge). ``n_i`` is ``e_i`` turned by +90 degrees.
- Its centre of gravity is at ``c_i = p_i + a_i e_i + b_i n_i`` (``cg_along`` a_i,
  ``cg_across`` b_i); ``inertia`` is its moment of inertia about the centre of gravity,
  about the hinge axes' direction [kg*m^2].

The equations of motion are ``M(q) q'' + h(q, q') = Q`` with :func:`mass_matrix` M,
:func:`velocity_terms` h (Coriolis and centrifugal) and generalised forces Q, of which
:func:`gravity_forces` gives a ground test's weight. In absolute angles Theta = T q (T
the lower triangular matrix of ones) the chain's terms are compact; the relative-angle
terms are ``M = T^T M_Theta T``, ``h = T^T h_Theta``, ``Q = T^T Q_Theta`` (the virtual
work of a force is the same in both sets of coordinates), computed here with suffix
sums.

Every function takes and returns plain float64 arrays and uses only NumPy and
:mod:`math` arithmetic in loops over the panels, so that numba can compile the same
source (``numba.njit(mass_matrix)``, tested): the dynamic core compiles these, it never
types them out again.
"""

import math

import numpy as np

from ecdsim._types import FloatArray


def absolute_angles(angles: FloatArray) -> FloatArray:
    """Each panel's angle from the base's x axis, ``Theta_i = q_1 + ... + q_i`` [rad].

    The relative angles of a serial chain add up (Spong et al. 2006, section 3.2, the
    planar elbow manipulator's forward kinematics).

    Parameters
    ----------
    angles : relative hinge angles q [rad], shape (n,)

    >>> absolute_angles(np.array([0.5, 1.0, -0.25])).tolist()
    [0.5, 1.5, 1.25]
    """
    n = angles.shape[0]
    theta = np.empty(n)
    total = 0.0
    for i in range(n):
        total += angles[i]
        theta[i] = total
    return theta


def hinge_positions(angles: FloatArray, length: FloatArray) -> FloatArray:
    """Positions of the hinges and of the wing tip, ``p_1 = 0, p_{i+1} = p_i + L_i e_i`` [m].

    Forward kinematics of a planar serial chain (Spong et al. 2006, section 3.2).

    Parameters
    ----------
    angles : relative hinge angles q [rad], shape (n,)
    length : hinge-to-hinge length of each panel L [m], shape (n,)

    Returns
    -------
    (n + 1, 2) array: row i is hinge i + 1's (x, y); the last row is the wing tip.

    >>> hinge_positions(np.array([0.0, np.pi / 2]), np.array([1.0, 2.0])).round(12).tolist()
    [[0.0, 0.0], [1.0, 0.0], [1.0, 2.0]]
    """
    theta = absolute_angles(angles)
    n = angles.shape[0]
    points = np.zeros((n + 1, 2))
    for i in range(n):
        points[i + 1, 0] = points[i, 0] + length[i] * math.cos(theta[i])
        points[i + 1, 1] = points[i, 1] + length[i] * math.sin(theta[i])
    return points


def cg_positions(
    angles: FloatArray, length: FloatArray, cg_along: FloatArray, cg_across: FloatArray
) -> FloatArray:
    """Each panel's centre of gravity, ``c_i = p_i + a_i e_i + b_i n_i`` [m].

    Forward kinematics (Spong et al. 2006, section 3.2) to a point fixed in panel i.

    Parameters
    ----------
    angles : relative hinge angles q [rad], shape (n,)
    length : hinge-to-hinge length L [m], shape (n,)
    cg_along : centre of gravity's distance along the panel from its inboard hinge a [m]
    cg_across : its offset across the panel, towards n_i [m]

    Returns
    -------
    (n, 2) array of (x, y).

    >>> cg_positions(np.array([np.pi / 2]), np.array([1.0]), np.array([0.5]),
    ...              np.array([0.1])).round(12).tolist()
    [[-0.1, 0.5]]
    """
    theta = absolute_angles(angles)
    points = hinge_positions(angles, length)
    n = angles.shape[0]
    out = np.empty((n, 2))
    for i in range(n):
        c, s = math.cos(theta[i]), math.sin(theta[i])
        out[i, 0] = points[i, 0] + cg_along[i] * c - cg_across[i] * s
        out[i, 1] = points[i, 1] + cg_along[i] * s + cg_across[i] * c
    return out


def panel_outlines(angles: FloatArray, length: FloatArray, thickness: FloatArray) -> FloatArray:
    """The outline of each panel in the plane: a rectangle from hinge to hinge [m].

    Corners ``p_i - t/2 n_i``, ``p_{i+1} - t/2 n_i``, ``p_{i+1} + t/2 n_i``,
    ``p_i + t/2 n_i`` (forward kinematics, Spong et al. 2006, section 3.2), for pictures
    of the wing's shape. The panel's thickness t is drawn about the hinge line: the
    model's panels are rigid bodies whatever their drawn outline.

    Parameters
    ----------
    angles : relative hinge angles q [rad], shape (n,)
    length : hinge-to-hinge length L [m], shape (n,)
    thickness : the drawn thickness of each panel t [m], shape (n,), >= 0

    Returns
    -------
    (n, 4, 2) array: four corners (x, y) per panel, in order around the rectangle.

    >>> panel_outlines(np.array([0.0]), np.array([2.0]), np.array([0.2])).round(12).tolist()
    [[[0.0, -0.1], [2.0, -0.1], [2.0, 0.1], [0.0, 0.1]]]
    """
    theta = absolute_angles(angles)
    points = hinge_positions(angles, length)
    n = angles.shape[0]
    out = np.empty((n, 4, 2))
    for i in range(n):
        half = 0.5 * thickness[i]
        nx, ny = -math.sin(theta[i]) * half, math.cos(theta[i]) * half
        out[i, 0, 0], out[i, 0, 1] = points[i, 0] - nx, points[i, 1] - ny
        out[i, 1, 0], out[i, 1, 1] = points[i + 1, 0] - nx, points[i + 1, 1] - ny
        out[i, 2, 0], out[i, 2, 1] = points[i + 1, 0] + nx, points[i + 1, 1] + ny
        out[i, 3, 0], out[i, 3, 1] = points[i, 0] + nx, points[i, 1] + ny
    return out


def _relative_from_absolute(matrix: FloatArray) -> FloatArray:
    """``T^T A T`` for the lower triangular matrix of ones T: 2-D suffix sums of A."""
    n = matrix.shape[0]
    out = np.zeros((n, n))
    for r in range(n - 1, -1, -1):
        for s in range(n - 1, -1, -1):
            total = matrix[r, s]
            if r + 1 < n:
                total += out[r + 1, s]
            if s + 1 < n:
                total += out[r, s + 1]
            if r + 1 < n and s + 1 < n:
                total -= out[r + 1, s + 1]
            out[r, s] = total
    return out


def _suffix_sums(values: FloatArray) -> FloatArray:
    """``T^T v``: element r is ``v_r + ... + v_n`` (generalised forces in relative angles)."""
    n = values.shape[0]
    out = np.empty(n)
    total = 0.0
    for r in range(n - 1, -1, -1):
        total += values[r]
        out[r] = total
    return out


def _outboard_masses(mass: FloatArray) -> FloatArray:
    """Element k is the mass of the panels beyond panel k, ``m_{k+1} + ... + m_n`` [kg]."""
    n = mass.shape[0]
    out = np.zeros(n)
    for k in range(n - 2, -1, -1):
        out[k] = out[k + 1] + mass[k + 1]
    return out


def mass_matrix(
    angles: FloatArray,
    mass: FloatArray,
    cg_along: FloatArray,
    cg_across: FloatArray,
    inertia: FloatArray,
    length: FloatArray,
) -> FloatArray:
    """The chain's mass matrix M(q) in relative hinge angles [kg*m^2].

    ``D(q) = sum_i m_i Jv_i^T Jv_i + I_i Jw_i^T Jw_i`` (Spong et al. 2006, section 7.3,
    Eq. for the inertia matrix of an n-link chain). In absolute angles, with the lever
    ``d_ij = L_j e_j`` of panel j < i and ``d_ii = a_i e_i + b_i n_i``, the velocity of
    c_i is ``sum_{j<=i} Theta_j' k x d_ij``, so

        M_Theta[j, k] = delta_jk I_j + sum_{i >= max(j, k)} m_i d_ij . d_ik
        M_Theta[k, k] = I_k + m_k (a_k^2 + b_k^2) + S_k L_k^2
        M_Theta[j, k] = m_k L_j (a_k cos D - b_k sin D) + S_k L_j L_k cos D  (j < k)

    with ``D = Theta_k - Theta_j`` and ``S_k`` the mass beyond panel k; then
    ``M = T^T M_Theta T``. Symmetric and positive definite for positive masses or
    inertias.

    Parameters
    ----------
    angles : relative hinge angles q [rad], shape (n,)
    mass : panel masses m [kg], shape (n,)
    cg_along : centre of gravity along each panel from its inboard hinge a [m]
    cg_across : centre of gravity across each panel b [m]
    inertia : each panel's moment of inertia about its centre of gravity [kg*m^2]
    length : hinge-to-hinge length of each panel L [m]

    Returns
    -------
    (n, n) array.

    One panel: its inertia about the hinge, ``I + m (a^2 + b^2)`` (parallel axes):

    >>> mass_matrix(np.array([0.3]), np.array([2.0]), np.array([0.5]), np.array([0.0]),
    ...             np.array([0.1]), np.array([1.0])).tolist()
    [[0.6]]
    """
    theta = absolute_angles(angles)
    outboard = _outboard_masses(mass)
    n = angles.shape[0]
    absolute = np.empty((n, n))
    for k in range(n):
        absolute[k, k] = (
            inertia[k]
            + mass[k] * (cg_along[k] * cg_along[k] + cg_across[k] * cg_across[k])
            + outboard[k] * length[k] * length[k]
        )
        for j in range(k):
            delta = theta[k] - theta[j]
            c, s = math.cos(delta), math.sin(delta)
            value = mass[k] * length[j] * (cg_along[k] * c - cg_across[k] * s)
            value += outboard[k] * length[j] * length[k] * c
            absolute[j, k] = value
            absolute[k, j] = value
    return _relative_from_absolute(absolute)


def velocity_terms(
    angles: FloatArray,
    rates: FloatArray,
    mass: FloatArray,
    cg_along: FloatArray,
    cg_across: FloatArray,
    length: FloatArray,
) -> FloatArray:
    """The Coriolis and centrifugal terms h(q, q') of ``M q'' + h = Q`` [N*m].

    ``h_k = sum_ij c_ijk q_i' q_j'`` with the Christoffel symbols of M (Spong et al.
    2006, section 7.4). For a planar chain they reduce to the centripetal accelerations
    of the panels: with absolute rates ``W = T q'`` and each centre of gravity's
    centripetal vector ``A_i = sum_{k<=i} W_k^2 d_ik``,

        h_Theta[j] = -sum_{i >= j} m_i (d_ij x A_i) . z,      h = T^T h_Theta

    (d'Alembert's principle with the acceleration ``sum_k W_k' z x d_ik - W_k^2 d_ik`` of
    c_i; the inertia about the centre of gravity adds no velocity term in a plane).

    Parameters
    ----------
    angles : relative hinge angles q [rad], shape (n,)
    rates : relative hinge angular speeds q' [rad/s], shape (n,)
    mass : panel masses m [kg]
    cg_along : centre of gravity along each panel a [m]
    cg_across : centre of gravity across each panel b [m]
    length : hinge-to-hinge length L [m]

    Returns
    -------
    (n,) array.

    Two panels at right angles turning rigidly together at W = 2 rad/s: no term at the
    root (every centripetal force points at it), ``h_2 = m_2 L_1 a_2 W^2`` at hinge 2:

    >>> velocity_terms(np.array([0.0, np.pi / 2]), np.array([2.0, 0.0]),
    ...                np.array([1.0, 1.0]), np.array([0.5, 0.5]), np.array([0.0, 0.0]),
    ...                np.array([1.0, 1.0])).round(12).tolist()
    [0.0, 2.0]
    """
    theta = absolute_angles(angles)
    omega = absolute_angles(rates)
    n = angles.shape[0]
    # Centripetal vector of the hinges (prefix sums) and of each centre of gravity.
    hx, hy = 0.0, 0.0
    ax = np.empty(n)
    ay = np.empty(n)
    for i in range(n):
        c, s = math.cos(theta[i]), math.sin(theta[i])
        w2 = omega[i] * omega[i]
        ax[i] = hx + w2 * (cg_along[i] * c - cg_across[i] * s)
        ay[i] = hy + w2 * (cg_along[i] * s + cg_across[i] * c)
        hx += w2 * length[i] * c
        hy += w2 * length[i] * s
    absolute = np.empty(n)
    sx, sy = 0.0, 0.0  # sum over the panels beyond j of m_i A_i
    for j in range(n - 1, -1, -1):
        c, s = math.cos(theta[j]), math.sin(theta[j])
        gx = cg_along[j] * c - cg_across[j] * s
        gy = cg_along[j] * s + cg_across[j] * c
        own = mass[j] * (gx * ay[j] - gy * ax[j])
        beyond = length[j] * (c * sy - s * sx)
        absolute[j] = -(own + beyond)
        sx += mass[j] * ax[j]
        sy += mass[j] * ay[j]
    return _suffix_sums(absolute)


def gravity_forces(
    angles: FloatArray,
    mass: FloatArray,
    cg_along: FloatArray,
    cg_across: FloatArray,
    length: FloatArray,
    offload: FloatArray,
    gravity_x: float,
    gravity_y: float,
) -> FloatArray:
    """Generalised forces of the weight in a ground test, ``Q = -dV/dq`` [N*m].

    Each panel's weight, less the fraction ``offload`` that the ground-support
    equipment carries at its centre of gravity, ``w_i = m_i (1 - o_i) g``, does the
    virtual work ``w_i . dc_i`` (Spong et al. 2006, section 7.3, potential energy
    ``V = -sum_i m_i g . c_i``):

        Q_Theta[j] = sum_{i >= j} (z x d_ij) . w_i,      Q = T^T Q_Theta

    Positive Q_k drives hinge k counter-clockwise. Gravity normal to the plane (the
    plane horizontal) does no work: give its in-plane components only.

    Parameters
    ----------
    angles : relative hinge angles q [rad], shape (n,)
    mass : panel masses m [kg]
    cg_along : centre of gravity along each panel a [m]
    cg_across : centre of gravity across each panel b [m]
    length : hinge-to-hinge length L [m]
    offload : fraction of each panel's weight carried by the support equipment [-], 0..1
    gravity_x : the gravity vector's component along the base's x axis [m/s^2]
    gravity_y : its component along the base's y axis [m/s^2]

    Returns
    -------
    (n,) array.

    A horizontal panel under downward gravity: its weight at the arm a pulls it down,
    ``Q = -m g a``:

    >>> gravity_forces(np.array([0.0]), np.array([2.0]), np.array([0.5]), np.array([0.0]),
    ...                np.array([1.0]), np.array([0.0]), 0.0, -10.0).tolist()
    [-10.0]
    """
    theta = absolute_angles(angles)
    n = angles.shape[0]
    absolute = np.empty(n)
    weight_beyond = 0.0  # sum over the panels beyond j of m_i (1 - o_i)
    for j in range(n - 1, -1, -1):
        c, s = math.cos(theta[j]), math.sin(theta[j])
        gx = cg_along[j] * c - cg_across[j] * s
        gy = cg_along[j] * s + cg_across[j] * c
        own = mass[j] * (1.0 - offload[j]) * (gx * gravity_y - gy * gravity_x)
        beyond = weight_beyond * length[j] * (c * gravity_y - s * gravity_x)
        absolute[j] = own + beyond
        weight_beyond += mass[j] * (1.0 - offload[j])
    return _suffix_sums(absolute)


def gravity_potential(
    angles: FloatArray,
    mass: FloatArray,
    cg_along: FloatArray,
    cg_across: FloatArray,
    length: FloatArray,
    offload: FloatArray,
    gravity_x: float,
    gravity_y: float,
) -> float:
    """Potential energy of the offloaded weights, ``V = -sum_i m_i (1 - o_i) g . c_i`` [J].

    Zero with every centre of gravity on the line through the root hinge normal to
    gravity (Spong et al. 2006, section 7.3). :func:`gravity_forces` is ``-dV/dq``.

    Parameters
    ----------
    angles : relative hinge angles q [rad], shape (n,)
    mass : panel masses m [kg]
    cg_along : centre of gravity along each panel a [m]
    cg_across : centre of gravity across each panel b [m]
    length : hinge-to-hinge length L [m]
    offload : fraction of each panel's weight carried by the ground-support equipment [-]
    gravity_x : gravity along the base's x axis [m/s^2]
    gravity_y : gravity along the base's y axis [m/s^2]

    >>> gravity_potential(np.array([np.pi / 2]), np.array([2.0]), np.array([0.5]),
    ...                   np.array([0.0]), np.array([1.0]), np.array([0.5]), 0.0, -10.0)
    5.0
    """
    centres = cg_positions(angles, length, cg_along, cg_across)
    total = 0.0
    for i in range(angles.shape[0]):
        weight = mass[i] * (1.0 - offload[i])
        total -= weight * (gravity_x * centres[i, 0] + gravity_y * centres[i, 1])
    return float(total)


def kinetic_energy(
    angles: FloatArray,
    rates: FloatArray,
    mass: FloatArray,
    cg_along: FloatArray,
    cg_across: FloatArray,
    inertia: FloatArray,
    length: FloatArray,
) -> float:
    """The chain's kinetic energy, ``sum_i m_i |c_i'|^2 / 2 + I_i Theta_i'^2 / 2`` [J].

    König's theorem per panel (Spong et al. 2006, section 7.3), from the velocities of
    the centres of gravity; equal to ``q'^T M(q) q' / 2`` (tested).

    Parameters
    ----------
    angles : relative hinge angles q [rad], shape (n,)
    rates : relative hinge angular speeds q' [rad/s], shape (n,)
    mass : panel masses m [kg]
    cg_along : centre of gravity along each panel a [m]
    cg_across : centre of gravity across each panel b [m]
    inertia : moment of inertia about each centre of gravity [kg*m^2]
    length : hinge-to-hinge length L [m]

    >>> kinetic_energy(np.array([0.0]), np.array([2.0]), np.array([2.0]), np.array([0.5]),
    ...                np.array([0.0]), np.array([0.1]), np.array([1.0]))
    1.2
    """
    theta = absolute_angles(angles)
    omega = absolute_angles(rates)
    total = 0.0
    vx, vy = 0.0, 0.0  # the inboard hinge's velocity
    for i in range(angles.shape[0]):
        c, s = math.cos(theta[i]), math.sin(theta[i])
        gx = cg_along[i] * c - cg_across[i] * s
        gy = cg_along[i] * s + cg_across[i] * c
        cx = vx - omega[i] * gy
        cy = vy + omega[i] * gx
        total += 0.5 * mass[i] * (cx * cx + cy * cy) + 0.5 * inertia[i] * omega[i] * omega[i]
        vx -= omega[i] * length[i] * s
        vy += omega[i] * length[i] * c
    return float(total)
