"""Linear stand-ins for the components: a Kelvin element (spring and dashpot in parallel)
with the interface of FmuComponent, and its coefficients from an FMU's response with
Eqs. 10.1-2 and 10.1-3 of the thesis (section 10.1, after Hagedorn and Wallaschek)."""

import math
from pathlib import Path

import numpy as np

from .fmu import FmuComponent


class KelvinElement:
    """Linear spring and dashpot in parallel about a static point:
    load = load0 + stiffness (x - x0) + damping * rate. It is linear and needs no FMU, so
    the host applies it exactly (no lag, no steps to take); as a contact it does not
    pull. It has FmuComponent's interface, so a host couples it the same way."""

    do_steps = saves = restores = 0

    def __init__(self, name, load_name, stiffness, damping, static_deflection, static_load,
                 unilateral=False):
        self.name = name
        self.load_name = load_name
        self.stiffness, self.damping = stiffness, damping
        self.static_deflection, self.static_load = static_deflection, static_load
        self.unilateral = unilateral
        self.deflection = static_deflection
        self.outputs = {}
        self._trial = None

    def host_load(self, deflection, rate=0.0):
        if self.unilateral and deflection <= 0.0:
            return 0.0
        load = (self.static_load + self.stiffness * (deflection - self.static_deflection)
                + self.damping * rate)
        return max(load, 0.0) if self.unilateral else load

    def _evaluate(self, deflection, rate):
        return {self.load_name: self.host_load(deflection, rate), "stiffness": self.stiffness}

    def start(self, time, deflection, rate=0.0):
        self.deflection, self.outputs = deflection, self._evaluate(deflection, rate)

    def begin_step(self):
        self._trial = None

    def trial(self, time, deflection, rate=0.0, pieces=1):
        self._trial = deflection, self._evaluate(deflection, rate)
        return self._trial[1]

    def accept(self):
        self.deflection, self.outputs = self._trial

    def reject(self):
        self._trial = None

    # The law is the element itself, whatever the scheme.
    def lagged_law(self):
        return self.host_load

    def predicted_law(self, time, linearised=None):
        return self.host_load

    def corrected_law(self):
        return self.host_load

    def load_scale(self, load):
        return max(abs(self.static_load), abs(load), 1e-12)

    @property
    def load(self):
        return self.outputs[self.load_name]

    def free(self):
        pass


def kelvin_coefficients(deflection, rate, load, moving_mass=0.0):
    """Equivalent linear stiffness and damping of a recorded response (whole cycles, or a
    long record), thesis section 10.1 after Hagedorn and Wallaschek, with mean values:

        c_eq = mean((F - mean F) * xdot) / mean(xdot^2)                       Eq. 10.1-2
        k_eq = (mean(F x) - mean F * mean x + m mean(xdot^2)) / (mean(x^2) - (mean x)^2)
                                                                              Eq. 10.1-3
    """
    x, xdot, force = (np.asarray(a, dtype=float) for a in (deflection, rate, load))
    c_eq = np.mean((force - force.mean()) * xdot) / np.mean(xdot ** 2)
    k_eq = ((np.mean(force * x) - force.mean() * x.mean() + moving_mass * np.mean(xdot ** 2))
            / (np.mean(x ** 2) - x.mean() ** 2))
    return float(k_eq), float(c_eq)


def harmonic_kelvin_equivalent(path, mean, amplitude, frequency, cycles=6, step=1e-3,
                               parameters=None):
    """Kelvin equivalent of an FMU about `mean` for the sine x = mean + amplitude
    sin(2 pi f t), from its response over the last two of `cycles` cycles (the first ones
    carry the start-up transient). The component has no moving mass of its own outside
    the FMU (m = 0 in Eq. 10.1-3). Returns (k_eq, c_eq, mean load over those cycles)."""
    component = FmuComponent(path, f"linearise_{Path(path).stem}", parameters=parameters)
    try:
        omega = 2.0 * math.pi * frequency
        samples_per_cycle = int(round(1.0 / (frequency * step)))
        n = cycles * samples_per_cycle
        t = np.arange(n + 1) * (1.0 / frequency / samples_per_cycle)
        x = mean + amplitude * np.sin(omega * t)
        component.start(0.0, x[0])
        load = np.empty(n + 1)
        load[0] = component.load
        for i in range(1, n + 1):
            component.begin_step()
            component.trial(t[i], x[i])
            component.accept()
            load[i] = component.load
    finally:
        component.free()
    # The last two cycles, each sample once (the end point closes the cycle).
    window = slice(n - 2 * samples_per_cycle, n)
    k_eq, c_eq = kelvin_coefficients(x[window], amplitude * omega * np.cos(omega * t[window]),
                                     load[window])
    return k_eq, c_eq, float(load[window].mean())
