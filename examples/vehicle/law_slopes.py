"""The Python path's slopes of a load law by central differences, for the vehicle's
analytic Jacobians (the contacts' tyres, the joints' bushes): by the deflection as the
coupling's bank takes them (bank.c's bank_law_loads), so that the two paths give the same
numbers; by the rate for a law with a damper term (a Kelvin element's; an FMU's law has
none)."""


def law_slope_step(x):
    """The step of the central difference by which the bank takes a law's slope at
    deflection x (bank.c's bank_law_loads): 1e-9 of |x|, at least 1e-15."""
    return 1e-9 * (abs(x) if abs(x) > 1e-6 else 1e-6)


def load_and_slopes(vehicle, component, x, rate):
    """A component's load at (x, rate) as the vehicle applies it (Vehicle.load) and its
    slopes by both, by central differences: by x a step of law_slope_step(x), by the rate
    a step of 1e-6 of |rate|, at least 1e-6."""
    step = law_slope_step(x)
    by_rate = 1e-6 * (abs(rate) if abs(rate) > 1.0 else 1.0)
    load = vehicle.load
    return (load(component, x, rate),
            (load(component, x + step, rate) - load(component, x - step, rate)) / (2.0 * step),
            (load(component, x, rate + by_rate) - load(component, x, rate - by_rate))
            / (2.0 * by_rate))
