"""The thesis's rotary damper as data: its variables, the gas spring's and the rotor's
values and the Table A6-1 dashpot curve, with where the thesis prints them, over the damper
equations of damper.py (spec section 3)."""

import math

from .damper import damper_equations
from .definition import POSITIVE, ComponentDefinition, Variable

# Table A6-1, "smoothed curve" column (rad/s, N.m). The printed table lost the 0.6 rad/s
# row on the compression side; it is restored by symmetry with the rebound side
# (reference_data/thesis/table_A6-1.csv keeps all three columns and the note).
DAMPER_TABLE_RATES = (
    -14.0, -13.0, -12.0, -11.0, -10.0, -9.0, -8.0, -7.0, -6.0, -5.0, -4.0, -3.0, -2.0,
    -1.8, -1.6, -1.4, -1.2, -1.0, -0.8, -0.6, -0.4, -0.2, -0.1, 0.0, 0.1, 0.2, 0.4, 0.6, 0.8,
    1.0, 1.2, 1.4, 1.6, 1.8, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0,
    14.0)
DAMPER_TABLE_TORQUES = (
    -8050.0, -8050.0, -8050.0, -8050.0, -7950.0, -7950.0, -7800.0, -7600.0, -7400.0, -7250.0,
    -7000.0, -6500.0, -6000.0, -5800.0, -5550.0, -5200.0, -4471.0, -3250.0, -2186.0, -1306.0,
    -622.0, -194.0, -100.0, 0.0, 100.0, 194.0, 622.0, 1306.0, 2186.0, 3250.0, 4471.0, 5856.0,
    7200.0, 8000.0, 8500.0, 10300.0, 11600.0, 12100.0, 12600.0, 12850.0, 13000.0, 13200.0,
    13400.0, 13550.0, 13550.0, 13650.0, 13650.0)
TABLE_SIZE = len(DAMPER_TABLE_RATES)


def _rate_name(i):
    return f"dashpot.rate[{i + 1}]"


def _torque_name(i):
    return f"dashpot.torque[{i + 1}]"


def damper_component():
    inputs = (
        Variable("angle", "input", "rad", "Wheel-arm angle theta relative to the hull, at the "
                 "damper rotor", 0.0, "deg"),
        Variable("angle_rate", "input", "rad/s", "Arm angular rate d(theta)/dt, held over each "
                 "communication step; positive in bump (compression)", 0.0, "deg/s"),
    )
    outputs = (
        Variable("torque", "output", "N.m", "Torque applied to the damper to produce the arm "
                 "motion: the gas-spring torque Tg (Eq. A5-16); steady rate gives Table A6-1"),
        Variable("gas_deflection", "output", "rad", "Gas-spring deflection xd = theta - "
                 "theta_r, bounded by |xd| < C2", display_unit="deg"),
        Variable("rotor_rate", "output", "rad/s", "Rate omega_r of the rotor node between gas "
                 "spring and dashpot", display_unit="deg/s"),
        Variable("dashpot_torque", "output", "N.m", "Dashpot torque Td(omega_r) from the "
                 "Table A6-1 curve (Appendix 6)"),
        Variable("stiffness", "output", "N.m/rad", "Instantaneous tangent stiffness "
                 "d torque/d theta, the gas-spring stiffness (rotor inertia holds theta_r)",
                 display_unit="N.m/deg"),
    )
    parameters = [
        Variable("C1", "parameter", "N.m", "Gas-spring torque constant C1 (Eq. A5-16; the "
                 "thesis prints 0.8e6 in N.mm, section 13.0)", 800.0, constraint=POSITIVE),
        Variable("C2", "parameter", "rad", "Gas-spring deflection limit C2 (Eq. A5-16, "
                 "section 13.0: 0.03 rad)", 0.03, "deg", POSITIVE),
        Variable("I", "parameter", "kg.m2", "Rotor inertia at the node between gas spring "
                 "and dashpot (section 12.6: 0.118 kg.m2)", 0.118, constraint=POSITIVE),
    ]
    for i, (rate, torque) in enumerate(zip(DAMPER_TABLE_RATES, DAMPER_TABLE_TORQUES)):
        parameters.append(Variable(_rate_name(i), "parameter", "rad/s", f"Dashpot curve point "
                                   f"{i + 1}: angular rate (Table A6-1)", rate, "deg/s"))
        parameters.append(Variable(_torque_name(i), "parameter", "N.m", f"Dashpot curve point "
                                   f"{i + 1}: torque, smoothed column (Table A6-1)", torque))
    states = (
        Variable("state.z", "local", "1", "Gas-spring coordinate z, xd = C2 tanh(z) (runtime/"
                 "damper.py)"),
        Variable("state.omega_r", "local", "rad/s", "Rate omega_r of the rotor node",
                 display_unit="deg/s"),
    )
    equations = damper_equations("C1", "C2", "I", [_rate_name(i) for i in range(TABLE_SIZE)],
                                 [_torque_name(i) for i in range(TABLE_SIZE)])

    return ComponentDefinition(
        "RotaryDamper",
        "Warrior rotary suspension damper at the wheel-arm pivot: Table A6-1 dashpot "
        "(laminar, turbulent, blow-off) in series with an isothermal entrapped-gas spring, "
        "rotor inertia between them (thesis chapters 9-14, Appendices 5 and 6).",
        inputs, outputs, parameters, states, equations,
        measured_ranges={"angle": (-math.pi / 4, math.pi / 4, "rotation about +/-45 deg, section 9.1"),
                         "angle_rate": (-14.0, 14.0, "Table A6-1 spans +/-14 rad/s")})


ROTARY_DAMPER = damper_component()
