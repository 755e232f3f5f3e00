"""The road-wheel station's plots (examples/road_wheel_station.py): PNG files."""

import math

import numpy as np

from coupling_study import STUDY_SCHEMES, STUDY_STEPS

STUDY_LABELS = {"hull_acceleration": "hull acceleration", "tyre_force": "tyre force",
                "damper_torque": "damper torque"}

# --- the runs -----------------------------------------------------------------------------

PANELS = (("hull_acceleration", "hull vertical\nacceleration (m/s2)", 1.0),
          ("hull_force", "force into\nhull (kN)", 1e-3),
          ("arm_angle", "arm angle from\nstatic, bump + (deg)", 180 / math.pi),
          ("damper_torque", "damper torque\n(kN.m)", 1e-3),
          ("tyre_force", "tyre force,\nwheel (kN)", 1e-3))


def plot_speed(path, speed, profile, nonlinear, linear):
    from plotting import plt, save_figure

    figure, axes = plt.subplots(len(PANELS) + 1, 1, figsize=(9, 12), sharex=True)
    t = nonlinear["time"]
    ground = [profile.height_and_slope(speed * ti)[0] * 1e3 for ti in t]
    axes[0].plot(t, ground, color="k")
    axes[0].set_ylabel("road under\nwheel (mm)")
    axes[0].set_title(f"Road-wheel station at {speed:g} m/s ({speed * 3.6:.0f} km/h): "
                      f"FMUs against linear Kelvin equivalents")
    for axis, (key, label, scale) in zip(axes[1:], PANELS):
        axis.plot(t, nonlinear[key] * scale, label="FMUs (nonlinear)", lw=1.0)
        axis.plot(linear["time"], linear[key] * scale, label="linear Kelvin equivalents",
                  lw=1.0, ls="--")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    # in the road panel, whose upper right is empty once the bump has passed: off the data
    axes[0].legend(*axes[1].get_legend_handles_labels(), loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time (s)")
    save_figure(figure, path)


def plot_difference(path, runs):
    """What the hull feels, nonlinear minus linear, for every speed."""
    from plotting import plt, save_figure

    figure, axes = plt.subplots(2, 1, figsize=(9, 7), sharex=False)
    for speed, (nonlinear, linear) in runs.items():
        distance = nonlinear["time"] * speed
        for axis, key, scale in ((axes[0], "hull_acceleration", 1.0),
                                 (axes[1], "hull_force", 1e-3)):
            difference = (nonlinear[key] - np.interp(nonlinear["time"], linear["time"],
                                                     linear[key])) * scale
            axis.plot(distance, difference, lw=0.8, label=f"{speed:g} m/s")
    axes[0].set_ylabel("hull acceleration,\nFMUs - linear (m/s2)")
    axes[1].set_ylabel("force into hull,\nFMUs - linear (kN)")
    for axis in axes:
        axis.set_xlabel("distance travelled (m)")
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    axes[0].set_title("Do the nonlinearities matter for the hull? Difference of the runs")
    save_figure(figure, path)


# --- coupling accuracy --------------------------------------------------------------------

def plot_study(path, table, steps=STUDY_STEPS, key="hull_acceleration"):
    from plotting import plt, save_figure

    figure, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    for axis, kind in zip(axes, ("total", "own")):
        for scheme in STUDY_SCHEMES:
            values = [(step * 1e3, table[scheme, step][kind][key]) for step in steps
                      if not isinstance(table[scheme, step], str)
                      and table[scheme, step][kind].get(key, 0.0) > 0.0]
            if values:
                axis.loglog(*zip(*values), "o-", label=scheme)
        axis.set_xlabel("host step (ms)")
        axis.set_ylabel(f"max error of the {STUDY_LABELS[key]}\n(% of its range)")
        axis.set_title("against the independent reference" if kind == "total" else
                       "against `converged` at the same step (the coupling's own)")
        axis.grid(alpha=0.3, which="both")
    axes[0].legend(fontsize=8)
    figure.suptitle("Road-wheel station: coupling error against host step (missing points: "
                    "the run failed)")
    save_figure(figure, path)
