"""The vehicle's equations in C outside exudyn (examples/vehicle/system.py, system.c;
docs/vehicle.md, The vehicle's equations in C): at states of a short run on the bump at
3 m/s, with the bank's laws of that step, the C assembly's forces, constraints, mass and
Jacobians against exudyn's own evaluation of the same model, its Jacobian against
central differences of its residual, and the solver's ordering holding every entry."""

import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'
STEP, END, PICKS = 1e-3, 0.03, (10, 30)  # host steps 10 and 30 of a 30 ms run
FACTORS = ((1.0, 0.0), (0.0, 1.0))  # K, then D


@pytest.fixture(scope="module")
def run(native_fmus):
    """(vehicle, {step: State}, exudyn's evaluation after the run)."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.course import Bump
    from vehicle.model import Vehicle
    from vehicle.system_states import ExudynEvaluation, run_states

    vehicle = Vehicle(Bump(3.0), 3.0, native_fmus["RoadWheelTyre"].parent)
    states = run_states(vehicle, END, STEP, set(PICKS))
    assert sorted(states) == list(PICKS)
    return vehicle, states, ExudynEvaluation(vehicle)


def _systems(run):
    from vehicle.system import VehicleSystem

    vehicle, states, exudyn = run
    for number in PICKS:
        state = states[number]
        exudyn.at(state)
        yield state, VehicleSystem(vehicle, state.laws), exudyn


def test_the_forces_constraints_and_mass_are_exudyns(run):
    for state, system, exudyn in _systems(run):
        f, g = system.residual(state.t, state.q, state.v)
        f_exudyn, g_exudyn = exudyn.forces()
        assert np.abs(f_exudyn).max() > 1e4  # the forces are there to compare
        assert np.abs(f - f_exudyn).max() <= 1e-13 * np.abs(f_exudyn).max()
        assert np.abs(g - g_exudyn).max() <= 1e-15  # m: both the joints' gap, to round-off
        mass = exudyn.mass()
        assert np.array_equal(np.diag(mass), system.mass_diagonal())
        assert not np.any(mass - np.diag(np.diag(mass)))


def test_the_jacobians_are_exudyns(run):
    """exudyn's ComputeJacobianODE2RHS is df/dq (df/dv): minus K (D). Where exudyn
    differentiates numerically (the dampers' connectors, their compiled law: the hull's and
    the damped arms' rotations) to 1e-6 of the entry, elsewhere to 1e-9."""
    from vehicle.system import dense

    vehicle = run[0]
    rotations = [vehicle.mbs.GetNodeODE2Index(node) + 2
                 for node in [vehicle.hull_node] + [vehicle.arm_nodes[i - 1]
                                                    for i in vehicle.dampers]]
    numerical = np.zeros((len(vehicle.mbs.systemData.GetODE2Coordinates()),) * 2, dtype=bool)
    numerical[np.ix_(rotations, rotations)] = True
    for state, system, exudyn in _systems(run):
        for factor, factor_t in FACTORS:
            ours = dense(system.jacobian(state.t, state.q, state.v, factor, factor_t),
                         system.n)
            theirs = -exudyn.jacobian(factor, factor_t)
            size = np.maximum(np.abs(ours), np.abs(theirs))
            off = np.abs(ours - theirs) - 1e-15 * size.max()
            assert np.all(off[~numerical] <= 1e-9 * size[~numerical])
            assert np.all(off[numerical] <= 1e-6 * size[numerical])
        G, _ = system.constraint_jacobian(state.q)
        rows, columns = exudyn.constraint_jacobian()
        assert np.array_equal(dense(G, system.m, system.n), rows)
        assert np.array_equal(dense(G, system.m, system.n).T, columns)


def _contacts_part(system, factor, factor_t):
    """The contacts' generalized forces and Jacobian in the system's coordinates, at the
    state last evaluated."""
    from vehicle.system import dense

    force = np.zeros(system.n)
    np.add.at(force, system.body_index, system.contacts.views["generalized"].reshape(-1))
    triplets = system.contacts.triplets(factor, factor_t).copy()
    triplets[:, :2] = system.body_index[triplets[:, :2].astype(int)]
    return force, dense(triplets, system.n)


def _differences(system, state, by, h):
    """Minus the central differences of the residual's f by q (by="q") or v, the
    contacts' part apart: (rest, contacts)."""
    n = system.n
    rest, contacts = np.zeros((n, n)), np.zeros((n, n))
    for j in range(n):
        sides = []
        for sign in (1.0, -1.0):
            q, v = state.q.copy(), state.v.copy()
            (q if by == "q" else v)[j] += sign * h
            f = system.residual(state.t, q, v)[0].copy()
            sides.append((f, _contacts_part(system, 0.0, 0.0)[0]))
        (f_plus, c_plus), (f_minus, c_minus) = sides
        contacts[:, j] = -(c_plus - c_minus) / (2 * h)
        rest[:, j] = -((f_plus - c_plus) - (f_minus - c_minus)) / (2 * h)
    return rest, contacts


def test_the_jacobian_is_the_derivative_of_the_residual(run):
    """Central differences of the C residual: all but the contacts to 1e-6 of the largest
    entry, the contacts (their kernel's Jacobian leaves a few terms out:
    tests/test_vehicle.py) to 1 % of theirs; the multipliers' force's derivative H."""
    from vehicle.system import dense

    for state, system, _ in _systems(run):
        for (factor, factor_t), by, h in zip(FACTORS, ("q", "v"), (1e-8, 1e-6)):
            K = dense(system.jacobian(state.t, state.q, state.v, factor, factor_t), system.n)
            K_contacts = _contacts_part(system, factor, factor_t)[1]
            rest, contacts = _differences(system, state, by, h)
            assert np.abs(K - K_contacts - rest).max() <= 1e-6 * np.abs(rest).max()
            assert np.abs(K_contacts - contacts).max() <= 1e-2 * np.abs(contacts).max()
        G, H = system.constraint_jacobian(state.q, state.multipliers)
        assert np.abs(state.multipliers).max() > 1e3  # the joints carry the hull
        h, n = 1e-7, system.n
        for j in range(n):
            sides = []
            for sign in (1.0, -1.0):
                q = state.q.copy()
                q[j] += sign * h
                sides.append(dense(system.constraint_jacobian(q)[0], system.m, n).T
                             @ state.multipliers)
            column = (sides[0] - sides[1]) / (2 * h)
            assert np.abs(dense(H, n)[:, j] - column).max() <= 1e-6 * np.abs(H[:, 2]).max()


def test_every_entry_falls_in_the_band_or_the_border(run):
    from vehicle.system import ordering, outside_band

    for state, system, _ in _systems(run):
        n, m = system.n, system.m
        order, half, border = ordering(system, border_link=5)
        assert sorted(order) == list(range(n + m))
        assert border == 3 * (1 + len(run[0].arm_nodes) + 1 + 1) + m
        K = system.jacobian(state.t, state.q, state.v, 1.0, 1.0)
        G, H = system.constraint_jacobian(state.q, state.multipliers)
        rows = np.concatenate([K[:, 0], G[:, 0] + n, G[:, 1], H[:, 0]])
        columns = np.concatenate([K[:, 1], G[:, 1], G[:, 0] + n, H[:, 1]])
        assert len(outside_band(order, half, border, rows, columns)) == 0
        # the check sees an order that does not hold: two of the band's links swapped
        swapped = order.copy()
        swapped[[0, 1, 2, 60, 61, 62]] = order[[60, 61, 62, 0, 1, 2]]
        assert len(outside_band(swapped, half, border, rows, columns)) > 0


BEND = np.radians(24.0)  # each of two joints in a row: a wheel's blend then reaches 2 links


def _sharp_bends(system, state, wheel):
    """state's q with the link beneath `wheel` moved under the wheel's centre and its two
    neighbours turned BEND towards the wheel about their joints with it (the track
    bending up round the wheel, as at the bump's foot at 5 m/s): (q, that link). The
    wheel's centre then lies within HANDOVER / 2 of both bisectors of the link's joints."""
    from vehicle import layout as lay

    q = state.q.copy()
    system.residual(state.t, q, state.v)
    centre = system.contacts.views["wheels"].reshape(-1, 2)[wheel]
    links = (system.reference + q)[system.link_index].reshape(-1, 3)
    u = np.stack([np.cos(links[:, 2]), np.sin(links[:, 2])], axis=1)
    r = centre - links[:, :2]
    along, height = np.sum(r * u, axis=1), r[:, 1] * u[:, 0] - r[:, 0] * u[:, 1]
    below = np.flatnonzero((height > 0.0) & (height < 2 * lay.WHEEL_RADIUS))
    k = below[np.argmin(np.abs(along[below]))]
    placed, half = links.copy(), 0.5 * lay.LINK_PITCH
    placed[k, :2] += along[k] * u[k]
    for side in (-1, 1):
        angle = links[k, 2] + side * BEND
        joint = placed[k, :2] + side * half * u[k]
        placed[k + side] = [*(joint + side * half * np.array([np.cos(angle), np.sin(angle)])),
                            angle]
    q[system.link_index] = placed.ravel() - system.reference[system.link_index]
    return q, k


def test_a_wheel_over_two_sharp_bends_reaches_two_links_left_out_of_the_band(run):
    """Where a wheel's blend reaches two links (beyond system.REACH): those entries are
    the residual's derivatives (central differences, to 1e-6 of the block), the ordering's
    band does not hold them, and the solver's Jacobian (keep_band) leaves exactly them
    out, counted; the rest unchanged."""
    from vehicle.system import VehicleSystem, dense, ordering, outside_band

    vehicle, states, _ = run
    state = states[PICKS[-1]]
    system = VehicleSystem(vehicle, state.laws)
    order, half, border = ordering(system)
    q, k = _sharp_bends(system, state, 0)
    K = system.jacobian(state.t, q, state.v, 1.0, 0.0).copy()
    outside = np.zeros(len(K), dtype=bool)
    outside[outside_band(order, half, border, K[:, 0], K[:, 1])] = True
    behind, ahead = (system.link_index[3 * j:3 * j + 3] for j in (k - 1, k + 1))
    pairs = {tuple(sorted(map(int, entry))) for entry in K[outside, :2]}
    assert pairs and all(a in behind and b in ahead for a, b in pairs)
    assert system.coordinate_name(int(behind[0])) == f"link {k - 1}'s x"
    block, h = dense(K, system.n)[np.ix_(behind, ahead)], 1e-8
    differences = np.zeros((3, 3))
    for j, column in enumerate(ahead):
        sides = []
        for sign in (1.0, -1.0):
            moved = q.copy()
            moved[column] += sign * h
            sides.append(system.residual(state.t, moved, state.v)[0][behind].copy())
        differences[:, j] = -(sides[0] - sides[1]) / (2 * h)
    assert np.abs(block).max() > 1e3  # N/m: entries there to compare
    assert np.abs(block - differences).max() <= 1e-6 * np.abs(block).max()
    system.keep_band(order, half, border)
    kept = system.jacobian(state.t, q, state.v, 1.0, 0.0)
    assert len(outside_band(order, half, border, kept[:, 0], kept[:, 1])) == 0
    assert np.array_equal(kept, K[~outside])
    assert system.left_out() == (outside.sum(), np.abs(K[outside, 2]).max())
