"""The registry of hinge effects (ecdsim.dynamics.kernel.effects): what it derives.

Every registered effect, at its parameters' example values, is held to what the built-in
effects are held to: its Jacobian terms against central differences of its torque
(rigid and compliant mesh), the compiled and plain kernels agreeing, the energy balance
closing with its dissipation, and each path refusing it unless it declares it (the
closed form). The layout, KNOWN_FIELDS and the effect bits are derived from the
declarations: checked here too, with the refusals of an unknown parameter.
"""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np
import pytest

from ecdsim.config.schema import CoreConfigSpec
from ecdsim.dynamics import DynamicParameters, DynamicProblem
from ecdsim.dynamics.kernel import effects, layout, loop
from ecdsim.dynamics.kernel.build import backend
from ecdsim.dynamics.solver import solve_dynamic
from tests import test_dynamics_kernel as kernel_tests
from tests.conftest import paper_system
from tests.dynamics_reference import assert_energy_closes

NAMES = [effect.name for effect in effects.REGISTRY]


def _examples(effect: effects.Effect) -> dict[str, float]:
    return {p.name: p.example for p in effect.parameters}


def _effect(name: str) -> effects.Effect:
    return next(e for e in effects.REGISTRY if e.name == name)


def test_the_layout_is_derived_from_the_declarations() -> None:
    # The parameters' columns follow EFFECTS, one each, before the discrete state; each
    # effect has a bit of its own after the built-in ones, which the kernel lists.
    columns = [effects.COLUMN[p.name] for p in effects.PARAMETERS]
    assert columns == list(range(layout.EFFECTS + 1, layout.COLUMNS))
    assert layout.MD_SLIDE0 == layout.COLUMNS
    bits = sorted(effects.BIT.values())
    assert len(set(bits)) == len(bits)
    for bit in bits:
        assert bit > layout.BUILT_IN_EFFECTS
        assert bit & layout.KERNEL_EFFECTS
    for effect in effects.REGISTRY:
        closed = bool(effects.BIT[effect.name] & layout.CLOSED_FORM_EFFECTS)
        assert closed == effect.closed_form


@pytest.mark.parametrize("name", NAMES)
def test_every_parameter_has_its_config_key(name: str) -> None:
    # `[section] key` exists in the config schema and reaches DynamicParameters.effects;
    # a parameter without one is a field of DynamicProblem (gravity's, set by predict).
    for p in _effect(name).parameters:
        if p.config is None:
            assert p.name in {f.name for f in fields(DynamicProblem)}, p.name
            continue
        section, key = p.config.split(".")
        spec_section = CoreConfigSpec.model_fields[section].annotation
        assert key in spec_section.model_fields, p.config  # type: ignore[union-attr]


def test_an_unknown_parameter_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown effect parameter 'no_such_drag'"):
        DynamicParameters(5.0, effects={"no_such_drag": 1.0})
    # A problem built without DynamicParameters (its dataclass directly) is refused by
    # the kernel's packer: a parameter nobody declared is never silently ignored.
    problem = kernel_tests._problem(paper_system(), DynamicParameters(5.0), [25.0])
    with pytest.raises(TypeError, match="no_such_drag"):
        solve_dynamic(replace(problem, effects={"no_such_drag": np.asarray(1.0)}))


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("mesh", ["rigid", "compliant"])
def test_the_jacobian_of_every_effect_matches_central_differences(
    name: str, mesh: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The check of test_dynamics_kernel (the same tolerances) on a case with the effect.
    values = _examples(_effect(name))
    if mesh == "rigid":
        params = DynamicParameters(5.0, static_friction_factor=1.5, stribeck_speed=0.02)
        sliding: tuple[float, ...] = (1.0,)
    else:
        params = DynamicParameters(
            5.0, rotor_inertia=2e-7, gear_stiffness=2e3, gear_mesh_damping=0.5
        )
        sliding = (1.0, 1.0)
    key = f"{name}, {mesh}"
    monkeypatch.setitem(
        kernel_tests.JACOBIAN_CASES, key, (replace(params, effects=values), sliding)
    )
    kernel_tests.test_the_jacobian_matches_central_differences(key)


@pytest.mark.parametrize("name", NAMES)
def test_every_effect_compiled_and_plain_with_its_energy(name: str) -> None:
    # Roll-off and heating with the effect: integrated segments throughout. The two
    # forms of the kernel agree (1e-12: the C library's roundings, as for the built-in
    # effects), and the balance closes with the effect's dissipation counted.
    params = replace(kernel_tests.CASES["rolloff and heating"], effects=_examples(_effect(name)))
    problem = kernel_tests._problem(paper_system(), params)
    compiled = solve_dynamic(problem, kernel=backend("numba"))
    plain = solve_dynamic(problem, kernel=backend("python"))
    assert compiled.events.names() == plain.events.names()
    for field in ("deployment_time", "final_angle", "max_speed", "final_temperature"):
        np.testing.assert_allclose(
            getattr(compiled, field), getattr(plain, field), rtol=1e-12, err_msg=field
        )
    assert_energy_closes(compiled)
    without = solve_dynamic(
        kernel_tests._problem(paper_system(), kernel_tests.CASES["rolloff and heating"])
    )
    # The effect acts: the deployment differs from the one without it.
    assert np.all(compiled.deployment_time != without.deployment_time)


@pytest.mark.parametrize("name", NAMES)
def test_the_closed_form_refuses_an_effect_it_does_not_declare(name: str) -> None:
    effect = _effect(name)
    params = DynamicParameters(5.0, effects=_examples(effect))
    case = kernel_tests._case(kernel_tests._problem(paper_system(), params, [25.0]), (1.0,))
    assert int(case.cw[layout.EFFECTS]) & effects.BIT[name]
    assert loop.closed_form_applies(case.cw, 1) == effect.closed_form
    # The same case without it is linear: the closed form takes it.
    case.cw[layout.EFFECTS] -= effects.BIT[name]
    assert loop.closed_form_applies(case.cw, 1)


@pytest.mark.parametrize("slope", [-1.5, 0.0, 1.2, 1.99])
def test_gravity_lists_every_angle_where_its_stiffness_balances_the_spring(slope: float) -> None:
    # The rest test examines where the push at rest k x + T_g can turn: T_g' = -k, i.e.
    # W cos(theta_0 + phi) = k. Its candidates are held to the roots found independently:
    # sign changes of W cos(theta_0 + phi) - k on a fine grid, refined by brentq.
    from scipy.optimize import brentq

    from ecdsim.physics.gravity import gravity_level_angle, gravity_level_count

    amplitude, release, lo, hi = 2.0, 0.3, -1.0, 11.0

    def balance(phi: float) -> float:
        return float(amplitude * np.cos(release + phi) - slope)

    grid = np.linspace(lo, hi, 20001)
    values = [balance(x) for x in grid]
    pairs = zip(grid[:-1], grid[1:], values[:-1], values[1:], strict=True)
    roots = [brentq(balance, a, b) for a, b, fa, fb in pairs if fa * fb < 0.0]
    count = gravity_level_count(slope, lo, hi, amplitude, release)
    listed = sorted(
        a for i in range(count)
        if lo <= (a := gravity_level_angle(slope, lo, hi, i, amplitude, release)) <= hi
    )  # fmt: skip
    np.testing.assert_allclose(listed, roots, atol=1e-9)  # brentq's default xtol 2e-12
    assert len(roots) >= 3  # the interval spans nearly two turns
    assert gravity_level_count(2.5, lo, hi, amplitude, release) == 0  # |k| > W: none
