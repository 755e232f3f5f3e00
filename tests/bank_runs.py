"""The bank's tests' prescribed host (test_bank.py, test_bank_first_law.py): a tyre, both
bushes and the damper driven through set motions, each step's passes to the scheme's
end, on the Python path (a Coupling of FmuComponents) and on the compiled path (a Bank)."""

import math

import numpy as np

from fmu_components.coupling import Coupling, FmuComponent
from fmu_components.coupling.bank import Bank


def mix(fmus, names=("tyre", "radial", "torsion", "damper")):
    made = {"tyre": lambda: FmuComponent(fmus["RoadWheelTyre"], "tyre", unilateral=True),
            "radial": lambda: FmuComponent(fmus["TrackBushRadial"], "radial"),
            "torsion": lambda: FmuComponent(fmus["TrackBushTorsion"], "torsion"),
            "damper": lambda: FmuComponent(fmus["RotaryDamper"], "damper")}
    return [made[name]() for name in names]


def motion(t, passes=0):
    """Each instance's deflection; the host's solution moves a little with each pass, so
    that every pass's law shows."""
    t = t + 1e-5 * passes
    return np.array([3e-3 + 1e-3 * math.sin(60 * t), 2e-4 + 1e-4 * math.sin(40 * t),
                     0.1 * math.sin(20 * t), 0.05 * math.sin(30 * t)])


def python_run(fmus, scheme, steps, step=1e-3, kinked=False, first=None):
    """(each step's accepted loads and its last laws at probes, the Coupling); `kinked`:
    the components' kinked first laws; `first`, a list: each step's first laws appended,
    with each component's accepted deflection, rate, stiffness, reverse stiffness and
    whether it is unilateral."""
    components = mix(fmus)
    for component in components:
        component.kinked_first_law = kinked
    coupling = Coupling(scheme)
    now = [0.0, 0]
    for i, component in enumerate(components):
        coupling.add(component, lambda i=i: (motion(*now)[i], 0.0))
    coupling.start(0.0)
    rows = []
    try:
        for k in range(1, steps + 1):
            now[:] = k * step, 0
            coupling.begin_step(now[0])
            if first is not None:
                first.append([(c.law, c.deflection, c.rate, c.stiffness, c.reverse_stiffness,
                               c.unilateral) for c in components])
            while coupling.end_pass(now[0]).repeat:
                now[1] += 1
            coupling.accept(now[0])
            probe = 1.01 * motion(now[0])
            rows.append([c.load for c in components]
                        + [c.law(x) for c, x in zip(components, probe)])
    finally:
        coupling.free()
    return np.array(rows), coupling


def bank_run(fmus, scheme, steps, step=1e-3, kinked=False, first=None):
    """python_run's on the compiled path (`first`: each step's first laws' rows)."""
    bank = Bank(mix(fmus), scheme)
    bank.kink_first_laws(kinked)
    bank.start(0.0, motion(0.0))
    rows = []
    try:
        for k in range(1, steps + 1):
            t, passes = k * step, 0
            bank.begin_step(t)
            if first is not None:
                first.append(bank.laws.copy())
            while bank.end_pass(t, motion(t, passes)).repeat:
                passes += 1
            bank.accept(t)
            rows.append(list(bank.loads) + list(bank.law_loads(1.01 * motion(t))))
    finally:
        bank.free()
    return np.array(rows), bank
