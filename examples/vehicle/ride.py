"""The figures the reduced vehicle's nonlinear and linear runs are compared by (peaks,
damper work, the seat's ISO 2631-1 Wk-weighted RMS: outputs.weighted_rms, the full
vehicle's)."""

import numpy as np
from scipy.integrate import cumulative_trapezoid

from .outputs import weighted_rms


def ride_figures(result):
    """Peak |hull vertical acceleration| at the CG and at the seat, the seat's Wk-weighted
    RMS over the run, and the work done on the dampers (J, each station's and their sum;
    positive: taken from the motion)."""
    seat = result["seat_acceleration"]
    work = [float(cumulative_trapezoid(result["damper_torque"][:, k],
                                       result["damper_rotation"][:, k])[-1])
            for k in range(result["damper_torque"].shape[1])]
    return {"peak_hull_acceleration": float(np.max(np.abs(result["hull_vertical_acceleration"]))),
            "peak_seat_acceleration": float(np.max(np.abs(seat))),
            "seat_wk_rms": weighted_rms(result["time"], seat),
            "peak_pitch_acceleration": float(np.max(np.abs(result["hull_pitch_acceleration"]))),
            "damper_work": work, "total_damper_work": sum(work),
            "peak_tyre_force": float(np.max(result["tyre_force"]))}
