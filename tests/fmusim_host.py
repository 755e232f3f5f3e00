"""A Co-Simulation host on fmpy's FMI 3.0 API that steps an FMU the way fmusim v0.0.39
(the Reference-FMUs' command-line importer, fmusim/FMI3CSSimulation.c) does, for machines
without fmusim:

* before each step it sets the inputs linearly interpolated from an input table at the
  step's start, which after an early return is the FMU's lastSuccessfulTime;
* with eventModeUsed it updates the discrete states after initialization and enters Event
  Mode (fmi3EnterEventMode, fmi3UpdateDiscreteStates, fmi3EnterStepMode) wherever a step
  asks for event handling, and then steps on without setting the inputs again;
* it records the outputs after every step, and again after every event.

A host that loops forever on an FMU is bounded here by a count of doStep calls: past it the
run fails instead of hanging.
"""

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

CLOSE = 1e-5  # fmusim's FMIIsClose: absolute, or relative for large values


def is_close(a, b):
    return abs(a - b) <= CLOSE or abs(a - b) <= CLOSE * max(abs(a), abs(b))


class StepLimitExceeded(AssertionError):
    pass


def interpolate(table, names, time):
    """The inputs at `time` as fmusim interpolates them: between the row before and the
    row after (x0 + (t - t0) (x1 - x0) / (t1 - t0)), the last row held."""
    times = table["time"]
    row = 0
    while row < len(times) - 1 and not times[row + 1] >= time:
        row += 1
    if row >= len(times) - 1:
        return [float(table[name][row]) for name in names]
    t0, t1 = times[row], times[row + 1]
    return [float(table[name][row] + (time - t0) * (table[name][row + 1] - table[name][row])
                  / (t1 - t0)) for name in names]


def run(path, table, stop_time, interval, early_return=False, event_mode=False,
        max_steps=None, stops=()):
    """Rows (time, *outputs) as fmusim records them, and the (time, eventHandlingNeeded)
    of every early return. `stops`: times where the host itself ends a step, as at an
    early return there (setting the inputs there before the next step)."""
    description = read_model_description(str(path))
    variables = description.modelVariables
    inputs = [v for v in variables if v.causality == "input"]
    outputs = [v for v in variables if v.causality == "output"]
    names = [v.name for v in inputs]
    input_vrs = [v.valueReference for v in inputs]
    output_vrs = [v.valueReference for v in outputs]
    fmu = FMU3Slave(guid=description.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=description.coSimulation.modelIdentifier,
                    instanceName="fmusim_host")
    fmu.instantiate(eventModeUsed=event_mode, earlyReturnAllowed=early_return)
    rows, returns = [], []
    max_steps = max_steps or 4 * int(round(stop_time / interval)) + 100
    try:
        fmu.enterInitializationMode(startTime=0.0)
        fmu.setFloat64(input_vrs, interpolate(table, names, 0.0))
        fmu.exitInitializationMode()
        if event_mode:
            fmu.updateDiscreteStates()
            fmu.enterStepMode()
        time, steps, calls, applied = 0.0, 0, 0, False
        rows.append((time, *fmu.getFloat64(output_vrs)))
        while not (time > stop_time or is_close(time, stop_time)):
            regular = (steps + 1) * interval
            end = min([regular] + [t for t in stops if time < t < regular])
            if not applied:
                fmu.setFloat64(input_vrs, interpolate(table, names, time))
            event, terminate, early, last = fmu.doStep(time, end - time)
            calls += 1
            if calls > max_steps:
                raise StepLimitExceeded(f"{calls} doStep calls for {stop_time / interval:.0f} "
                                        f"steps: no progress from t = {time!r} s")
            if early:
                returns.append((last, event))
            time = last if early and last < end else end
            if is_close(time, regular):
                steps += 1
            rows.append((time, *fmu.getFloat64(output_vrs)))
            assert not terminate
            applied = False
            if event_mode and event:
                fmu.enterEventMode()
                fmu.updateDiscreteStates()
                fmu.enterStepMode()
                rows.append((time, *fmu.getFloat64(output_vrs)))
                applied = True
        fmu.terminate()
    finally:
        fmu.freeInstance()
    table = np.array(rows, dtype=[("time", float)] + [(v.name, float) for v in outputs])
    return table, returns
