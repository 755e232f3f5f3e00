"""The load a host applies for a component between two FMU steps: a law about a point
(x*, F*) the FMU has reached or is predicted to reach,

    F(x, v) = F* + K_s(x) (x - x*),   K_s(x) = K + Q (x - x*) / 2,

evaluated at every iterate of the host's solver (its Newton iterations, its numerical
Jacobian). K is the component's tangent over the step and Q its change with deflection
(the curvature of the elastic force, Eq. 5.3.1-3 for the tyre), so K_s is the secant to
x. K_s is kept within [K/2, 2K], which keeps the law monotone where the parabola would
turn. A host that differentiates its force elements has the law's slope in its
Jacobian: the component is implicit in it and explicit only in what it does not predict.

A reversal. The rubber components' answer to a step has a kink where the step's motion
changes direction, at the deflection the step starts from: their viscoelastic branches
slip like friction elements (Eq. 4.2.7-2, dF/dx = k (1 - sgn(v) F / c)), so the tangent
for unloading is up to four times that for loading (a track bush at 40 kN: 98 and
395 MN/m). Where the law's `side` is +1 or -1, the law above holds on that side of the
`kink` and beyond it the load goes on from the law's value there with the tangent
`beyond`, the FMU's tangent for motion the other way; `side` 0 is no kink.

A contact (the tyre) is unilateral: no load at x <= 0 and never a pulling load. About a
point where the FMU carries no load (out of contact, or the rubber not yet back), the law
is the contact's stiffness from first touch, max(0, K_touch (x - max(x*, 0))), so that a
host iterate that presses in meets the contact instead of empty space.
"""


from dataclasses import dataclass, field


@dataclass(slots=True)
class LoadLaw:
    deflection: float  # x*
    load: float  # F*
    stiffness: float  # K
    curvature: float = 0.0  # Q
    unilateral: bool = False
    touch_stiffness: float = 0.0  # a contact's stiffness from first touch
    kink: float = None  # where the step's motion reverses (default x*)
    beyond: float = None  # the tangent beyond the kink (default K)
    side: float = 0.0  # +1 or -1: the side of the kink the law about x* holds on; 0: none
    kink_load: float = field(init=False)  # the law's load at the kink

    def __post_init__(self):
        if self.kink is None:
            self.kink = self.deflection
        if self.beyond is None:
            self.beyond = self.stiffness
        self.kink_load = self._about(self.kink)

    def secant(self, deflection):
        """Slope of the law from x* to `deflection`."""
        k = self.stiffness
        if not self.curvature:
            return k
        secant = k + 0.5 * self.curvature * (deflection - self.deflection)
        low, high = (0.5 * k, 2.0 * k) if k >= 0.0 else (2.0 * k, 0.5 * k)
        return min(max(secant, low), high)

    def __call__(self, deflection, rate=0.0):
        """The load at the host's deflection; `rate` is not used (the FMU's answer to the
        rate arrives with its step)."""
        if self.unilateral:
            if deflection <= 0.0:
                return 0.0
            if self.load <= 0.0:
                return max(0.0, self.touch_stiffness * (deflection - max(self.deflection, 0.0)))
        if self.side * (deflection - self.kink) < 0.0:
            load = self.kink_load + self.beyond * (deflection - self.kink)
        else:
            load = self._about(deflection)
        return max(load, 0.0) if self.unilateral else load

    def _about(self, deflection):
        """The law about x* (its secant from there), without the kink or the contact."""
        return self.load + self.secant(deflection) * (deflection - self.deflection)
