"""A small host for the coupling library's tests: a mass on one component, pressed onto
it by gravity and driven through it by a ground that moves as prescribed.

    m z'' = F(x, x') - m g,   x = ground(t) - z   (the component's deflection)

integrated by Newmark's average acceleration (trapezoidal, second order) with Newton on
the component's load law, and coupled by the library's step protocol: begin_step, a solve,
end_pass (repeat the solve, retry shorter, or accept), accept. It can also give a step up
on its own (reject_every), as an adaptive host does.
"""

import numpy as np

from fmu_components.coupling import Coupling


class MassHost:
    def __init__(self, component, mass, ground, ground_rate, scheme="corrected",
                 gravity=9.81, reject_every=0):
        self.component = component
        self.mass, self.gravity = mass, gravity
        self.ground, self.ground_rate = ground, ground_rate
        self.reject_every = reject_every
        self.coupling = Coupling(scheme, record=self._record)
        self.coupling.add(component, self._state)
        self.t = 0.0
        self.z = self.v = self.a = 0.0
        self._trial = None  # (t, z, v) of the solve in progress
        self.records = []
        self.step_sizes = []
        self.rejected = 0

    def _state(self):
        t, z, v = self._trial if self._trial else (self.t, self.z, self.v)
        return self.ground(t) - z, self.ground_rate(t) - v

    def equilibrium(self, z_guess=0.0):
        """The static state: z where the relaxed component carries the weight."""
        z = z_guess
        for _ in range(50):
            x = self.ground(0.0) - z
            load = self.component.host_load(x)
            slope = (self.component.host_load(x + 1e-9) - load) / 1e-9
            z -= (self.mass * self.gravity - load) / slope
        self.z = z
        return z

    def _record(self, t):
        x, _ = self._state()
        self.records.append((t, self.a, self.component.outputs[self.component.load_name], x))

    def _solve(self, h):
        """Newmark average acceleration to t + h with the component's current law."""
        t1 = self.t + h
        z = self.z + h * self.v + 0.25 * h * h * self.a  # predictor: a_{n+1} = a_n
        for _ in range(30):
            a = 4.0 / h ** 2 * (z - self.z - h * self.v) - self.a
            v = self.v + 0.5 * h * (self.a + a)
            self._trial = (t1, z, v)
            x, rate = self._state()
            residual = self.mass * a - self.component.host_load(x, rate) + self.mass * self.gravity
            dz = 1e-9
            self._trial = (t1, z + dz, v + 2.0 / h * dz)
            x2, rate2 = self._state()
            slope = (4.0 / h ** 2 * self.mass
                     - (self.component.host_load(x2, rate2) - self.component.host_load(x, rate))
                     / dz)
            step = residual / slope
            z -= step
            if abs(step) < 1e-15 + 1e-12 * abs(z):
                break
        a = 4.0 / h ** 2 * (z - self.z - h * self.v) - self.a
        v = self.v + 0.5 * h * (self.a + a)
        self._trial = (t1, z, v)
        return a

    def run(self, end_time, step):
        coupling = self.coupling
        self._trial = None
        coupling.start(0.0)
        x, rate = self._state()
        self.a = (self.component.load - self.mass * self.gravity) / self.mass
        self._record(0.0)
        steps = 0
        while self.t < end_time - 1e-12:
            h = min(step, end_time - self.t)
            while True:
                coupling.begin_step(self.t + h)
                while True:
                    a = self._solve(h)
                    verdict = coupling.end_pass(self.t + h)
                    if not verdict.repeat:
                        break
                if verdict.retry_step is None:
                    break
                h = verdict.retry_step
                self._trial = None
            steps += 1
            if self.reject_every and steps % self.reject_every == 0:
                # the host gives this step up (say its own error control refused it)
                coupling.reject()
                self.rejected += 1
                self._trial = None
                coupling.begin_step(self.t + h)
                while True:
                    a = self._solve(h)
                    if not coupling.end_pass(self.t + h).repeat:
                        break
            t1, z, v = self._trial
            self._trial = None
            self.t, self.z, self.v, self.a = t1, z, v, a
            self.step_sizes.append(h)
            coupling.accept(t1)
        coupling.free()
        data = np.array(self.records)
        return {"time": data[:, 0], "acceleration": data[:, 1], "load": data[:, 2],
                "deflection": data[:, 3]}
