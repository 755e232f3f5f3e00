"""What a run records and writes: histories, figures of merit (peaks, damper work, the
ISO 2631-1 Wk-weighted rms acceleration at the driver's seat), CSV columns, plots of the
time histories and of the track's shape, and an animation."""

import ctypes
import math

import numpy as np
from scipy import signal
from scipy.integrate import cumulative_trapezoid

from . import joints
from . import layout as lay
from .bush_shear import seat_offsets, warn_across_track


def exudyn_state(mbs):
    """(q, v, a), the present state in exudyn's data."""
    data = mbs.systemData
    return (np.asarray(data.GetODE2Coordinates()), np.asarray(data.GetODE2Coordinates_t()),
            np.asarray(data.GetODE2Coordinates_tt()))


def record(vehicle, t):
    """Vehicle._record: the accepted state at t (the one its host gives,
    Vehicle.given_state, else exudyn's data) checked (Contacts.check, which evaluates the
    contacts there), the step check's start kept (StepCheck.accepted) and its values
    written (Records.write)."""
    q, qd, a = vehicle.given_state or exudyn_state(vehicle.mbs)
    vehicle.contacts.check(t, q, qd)
    if vehicle.step_check is not None:
        vehicle.step_check.accepted()
    if vehicle.records is None:
        vehicle.records = Records(vehicle)
    vehicle.records.write(t, a)


# the values each accepted step keeps: one number each, a row's first columns
SCALARS = ("time", "hull_vertical_acceleration", "hull_pitch_acceleration",
           "hull_surge_acceleration", "seat_vertical_acceleration", "hull_x", "hull_y",
           "hull_pitch", "hull_surge_velocity", "drive_torque", "ground_load")
# and arrays, in the row after them: the record's name, the contacts' result it copies
COPIED = (("tyre_compression", "compression"), ("pins", "pins"), ("wheels", "wheels"),
          ("idler", "idler"), ("seats", "seats"), ("directions", "u"))


class _Source(ctypes.Structure):
    """records.c's RecordSource."""
    _fields_ = [("data", ctypes.c_void_p), ("index", ctypes.c_void_p),
                ("count", ctypes.c_int), ("stride", ctypes.c_int)]


class Records:
    """What is kept after each accepted step: the system's values as they are, a row per
    step of an array made once (twice as long when full), the histories picked out of it
    after the run (histories), so that a step's record costs little: the contacts'
    results copied from their last evaluation, the bank's loads and deflections, in one
    C call (records.c) where they are in the C kernel's memory and the bank's arrays, else
    by numpy (the same values)."""

    def __init__(self, vehicle, capacity=1024):
        self.v, self.count = vehicle, 0
        contacts = vehicle.contacts
        self.hull = vehicle.mbs.GetNodeODE2Index(vehicle.hull_node)
        n = len(vehicle.components)
        self.shapes = {name: np.shape(contacts.last(source)[0]) for name, source in COPIED}
        self.shapes.update(loads=(n,), deflections=(n,))
        self.columns, at = {}, len(SCALARS)  # each array's columns in a row
        for name, shape in self.shapes.items():
            self.columns[name] = slice(at, at + math.prod(shape))
            at += math.prod(shape)
        self._rows(np.empty((capacity, at)))
        self._gather = None  # (bank, lib, sources, their count) once made

    def _rows(self, rows):
        self.rows, self._rows_at = rows, rows.ctypes.data

    def _sources(self):
        """records.c's sources where the contacts' last evaluation is the C kernel's and
        the bank's arrays are the run's, else None."""
        contacts, bank = self.v.contacts, self.v.bank
        if bank is None or not contacts.by_compiled():
            return None
        if self._gather is None or self._gather[0] is not bank:
            lib = joints.library()
            if lib is None:
                return None
            lib.records_gather.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p]
            if lib.records_layout() != ctypes.sizeof(_Source):
                raise RuntimeError("records.c and outputs.py disagree on the layout")
            cells = np.ascontiguousarray(bank.load_cells, dtype=np.int_)
            sources = (_Source * (len(COPIED) + 2))(
                *[_Source(contacts.last(source)[1], None, int(np.prod(self.shapes[name])), 1)
                  for name, source in COPIED],
                _Source(bank.outputs.ctypes.data, cells.ctypes.data, bank.n, 1),
                _Source(bank.accepted.ctypes.data + bank.accepted.itemsize, None, bank.n,
                        bank.accepted.shape[1]))
            self._gather = (bank, lib, ctypes.addressof(sources), len(sources), (sources,
                                                                                cells))
        return self._gather

    def write(self, t, a):
        """The values at the accepted state at t, whose accelerations are a (the contacts'
        last evaluation there)."""
        i = self.count
        if i == len(self.rows):
            self._rows(np.concatenate([self.rows, np.empty_like(self.rows)]))
        row, contacts, hull = self.rows[i], self.v.contacts, self.hull
        gather = self._sources()
        if gather is not None:
            _, lib, sources, count, _ = gather
            lib.records_gather(count, sources,  # the arrays' columns, after the scalars
                               self._rows_at + i * row.nbytes + row.itemsize * len(SCALARS))
        else:
            columns = self.columns
            for name, source in COPIED:
                row[columns[name]] = np.ravel(contacts.last(source)[0])
            row[columns["loads"]], row[columns["deflections"]] = self.v.accepted()
        acceleration, angular = a[hull:hull + 2], a[hull + 2]
        state, rate = contacts.last("hull")[0], contacts.last("hull_v")[0]
        omega, theta = rate[2], state[2]
        seat = (math.cos(theta) * lay.SEAT[0] - math.sin(theta) * lay.SEAT[1],
                math.sin(theta) * lay.SEAT[0] + math.cos(theta) * lay.SEAT[1])
        row[:len(SCALARS)] = (
            t, acceleration[1], angular, acceleration[0],
            acceleration[1] + angular * seat[0] - omega ** 2 * seat[1],
            state[0], state[1], theta, rate[0], contacts.last("drive_torque")[0].flat[0],
            contacts.last("ground_load")[0].sum())
        self.count = i + 1

    def stacked(self):
        """Each value's history (a new array): the scalars by name, the arrays."""
        rows = self.rows[:self.count]
        values = {name: np.ascontiguousarray(rows[:, k]) for k, name in enumerate(SCALARS)}
        values.update({name: np.ascontiguousarray(rows[:, self.columns[name]]).reshape(
            (self.count,) + shape) for name, shape in self.shapes.items()})
        return values


def histories(vehicle):
    """The run's histories from its records (Records): each column one step."""
    stacked = vehicle.records.stacked()
    loads, deflections = stacked.pop("loads"), stacked.pop("deflections")
    sprocket_joint, idler_joint = vehicle.contacts.tension_joints(
        np.stack([stacked[key] for key in ("hull_x", "hull_y", "hull_pitch")], axis=1),
        stacked["pins"]).T
    rows = {kind: np.array(rows) for kind, rows in vehicle.rows.items()}
    radial = loads[:, rows["radial"]]
    steps = np.arange(vehicle.records.count)
    result = {key: stacked[key] for key in ("time", "hull_vertical_acceleration",
                                            "hull_pitch_acceleration",
                                            "hull_surge_acceleration",
                                            "seat_vertical_acceleration", "hull_x", "hull_y",
                                            "hull_pitch", "hull_surge_velocity")}
    along, across = seat_offsets(stacked.pop("seats"), stacked.pop("directions"))
    result.update({
        "tyre_force": loads[:, rows["tyre"]].sum(axis=2),
        "tyre_compression": stacked["tyre_compression"],
        "damper_torque": loads[:, rows["damper"]],
        "damper_angle": deflections[:, rows["damper"]],
        "bush_radial_force": radial,
        "bush_radial_deflection": deflections[:, rows["radial"]],
        "bush_torque": loads[:, rows["torsion"]],
        "bush_angle": deflections[:, rows["torsion"]],
        "bush_seat_along": along, "bush_seat_across": across,
        "track_tension_sprocket": radial[steps, sprocket_joint],
        "track_tension_idler": radial[steps, idler_joint],
    })
    result.update({key: stacked[key] for key in ("drive_torque", "ground_load", "pins",
                                                 "wheels", "idler")})
    result["damper_stations"] = list(vehicle.dampers)
    # radial loads across the track are not tension: the run says where (bush_shear.py)
    result["across_track"] = warn_across_track(result, vehicle.contacts)
    # work done on each damper (J): what it dissipates, and what its gas spring holds
    result["damper_work"] = np.array([
        cumulative_trapezoid(result["damper_torque"][:, i], result["damper_angle"][:, i],
                             initial=0)[-1] for i in range(result["damper_torque"].shape[1])])
    return result


# --- ISO 2631-1 frequency weighting Wk (vertical, seated) ----------------------------------

def largest_difference(result, other, keys):
    """The largest difference between two runs' histories of `keys` (the same times), each
    in % of its range in `result` (over all its columns: all tyres, all bushes), and
    the key where it is."""
    if not np.array_equal(result["time"], other["time"]):
        raise ValueError("the two runs' histories are not at the same times")
    worst = (0.0, None)
    for key in keys:
        a, b = np.asarray(result[key], dtype=float), np.asarray(other[key], dtype=float)
        span = np.ptp(a)
        if not span > 0:
            raise ValueError(f"{key}: nothing to compare (no range)")
        difference = float(np.max(np.abs(a - b))) / span * 100
        if worst[1] is None or difference > worst[0]:  # the first key's of equal ones
            worst = (difference, key)
    return worst


def _quadratic(f, q):
    w = 2 * math.pi * f
    return np.array([1 / w ** 2, 1 / (q * w), 1.0])


def wk_weighting():
    """Wk of ISO 2631-1:1997 (Annex A): band limits 0.4 and 100 Hz, a-v transition
    (f3 = f4 = 12.5 Hz, Q4 = 0.63) and upward step (f5 = 2.37 Hz, Q5 = 0.91, f6 = 3.35 Hz,
    Q6 = 0.91), as a continuous transfer function (numerator, denominator)."""
    w1, w2, w3 = 2 * math.pi * 0.4, 2 * math.pi * 100.0, 2 * math.pi * 12.5
    q = 1 / math.sqrt(2)
    high = (np.array([1.0, 0, 0]), np.array([1.0, w1 / q, w1 ** 2]))
    low = (np.array([w2 ** 2]), np.array([1.0, w2 / q, w2 ** 2]))
    transition = (np.array([1 / w3, 1.0]), _quadratic(12.5, 0.63))
    # the step's gain is (f5/f6)^2 below it and 1 above
    step = (_quadratic(2.37, 0.91) * (2.37 / 3.35) ** 2, _quadratic(3.35, 0.91))
    num, den = np.array([1.0]), np.array([1.0])
    for b, a in (high, low, transition, step):
        num, den = np.polymul(num, b), np.polymul(den, a)
    return num, den


def weighted_rms(time, acceleration, settle=0.0):
    """Wk-weighted rms (m/s2) of an acceleration history, from `settle` s on; resampled
    at the history's smallest step first (exudyn shortens a step where it must)."""
    recorded = np.asarray(time)
    step = max(np.min(np.diff(recorded)), 1e-6)
    t = np.arange(recorded[0], recorded[-1] + 0.5 * step, step)
    a = np.interp(t, recorded, np.asarray(acceleration) - np.asarray(acceleration)[0])
    if len(t) < 2:
        return 0.0
    _, weighted, _ = signal.lsim(wk_weighting(), a, t - t[0])
    keep = t >= settle
    return float(np.sqrt(np.mean(weighted[keep] ** 2)))


def figures(result):
    """The figures the summary prints and the linear alternative is compared on."""
    a = result["hull_vertical_acceleration"]
    return {
        "peak_hull_vertical_acceleration": float(np.max(np.abs(a - a[0]))),
        "peak_hull_pitch_acceleration": float(np.max(np.abs(result["hull_pitch_acceleration"]))),
        "peak_seat_acceleration": float(np.max(np.abs(result["seat_vertical_acceleration"]
                                                      - result["seat_vertical_acceleration"][0]))),
        "seat_wk_rms": weighted_rms(result["time"], result["seat_vertical_acceleration"]),
        "max_tyre_force": float(result["tyre_force"].max()),
        "max_tension_sprocket": float(result["track_tension_sprocket"].max()),
        "max_tension_idler": float(result["track_tension_idler"].max()),
        "peak_damper_torque": float(np.abs(result["damper_torque"]).max()),
        "damper_work": float(result["damper_work"].sum()),
    }


FIGURE_LABELS = (
    ("peak_hull_vertical_acceleration", "peak hull vertical acceleration (CG)", "m/s2", 1.0),
    ("peak_hull_pitch_acceleration", "peak hull pitch acceleration", "rad/s2", 1.0),
    ("peak_seat_acceleration", "peak vertical acceleration, driver's seat", "m/s2", 1.0),
    ("seat_wk_rms", "Wk-weighted rms acceleration, driver's seat (ISO 2631-1)", "m/s2", 1.0),
    ("max_tyre_force", "max wheel tyre force", "kN", 1e-3),
    ("max_tension_sprocket", "max track tension at the sprocket", "kN", 1e-3),
    ("max_tension_idler", "max track tension at the idler", "kN", 1e-3),
    ("peak_damper_torque", "peak damper torque", "kN.m", 1e-3),
    ("damper_work", "work done on the dampers", "kJ", 1e-3),
)


CSV_UNITS = {
    "time": "s", "hull_vertical_acceleration": "m/s2", "hull_pitch_acceleration": "rad/s2",
    "hull_surge_acceleration": "m/s2", "seat_vertical_acceleration": "m/s2", "hull_x": "m",
    "hull_y": "m", "hull_pitch": "rad", "hull_surge_velocity": "m/s",
    "track_tension_sprocket": "N", "track_tension_idler": "N", "drive_torque": "N.m",
    "ground_load": "N", "tyre_force": "N", "tyre_compression": "m", "damper_torque": "N.m",
    "damper_angle": "rad", "bush_radial_force": "N", "bush_radial_deflection": "m",
    "bush_torque": "N.m", "bush_angle": "rad"}


def csv_columns(result):
    stations = result["damper_stations"]
    columns = {name: result[name] for name in (
        "time", "hull_vertical_acceleration", "hull_pitch_acceleration",
        "hull_surge_acceleration", "seat_vertical_acceleration", "hull_x", "hull_y",
        "hull_pitch", "hull_surge_velocity", "track_tension_sprocket", "track_tension_idler",
        "drive_torque", "ground_load")}
    for name in ("tyre_force", "tyre_compression"):
        columns[name] = [(f"{name}_{w + 1}", result[name][:, w])
                         for w in range(result[name].shape[1])]
    for name in ("damper_torque", "damper_angle"):
        columns[name] = [(f"{name}_{s}", result[name][:, i]) for i, s in enumerate(stations)]
    for name in ("bush_radial_force", "bush_radial_deflection", "bush_torque", "bush_angle"):
        columns[name] = [(f"{name}_{j}", result[name][:, j])
                         for j in range(result[name].shape[1])]
    return columns


# --- plots ---------------------------------------------------------------------------------

def plot_histories(path, result, linear, title):
    from plotting import plt, save_figure

    panels = (("hull_vertical_acceleration", "hull vertical\nacceleration, CG (m/s2)", 1.0),
              ("seat_vertical_acceleration", "vertical acceleration,\ndriver's seat (m/s2)", 1.0),
              ("hull_pitch_acceleration", "hull pitch\nacceleration (rad/s2)", 1.0),
              ("tyre_force", "wheel tyre\nforce (kN)", 1e-3),
              ("damper_torque", "damper torque\n(kN.m)", 1e-3),
              ("track_tension_sprocket", "track tension (kN)\nsprocket -, idler --", 1e-3))
    figure, axes = plt.subplots(len(panels), 1, figsize=(9, 14), sharex=True)
    t = result["time"]
    for axis, (key, label, scale) in zip(axes, panels):
        values = result[key] * scale
        if values.ndim == 1:
            axis.plot(t, values, lw=1.0, label="FMUs")
            if linear is not None:
                axis.plot(linear["time"], linear[key] * scale, lw=1.0, ls="--",
                          label="linear Kelvin")
        else:
            names = (result["damper_stations"] if key == "damper_torque"
                     else range(1, values.shape[1] + 1))
            for i, name in enumerate(names):
                axis.plot(t, values[:, i], lw=0.8, label=f"station {name}")
            axis.legend(fontsize=7, ncol=3, loc="upper left", bbox_to_anchor=(1.01, 1.0))
        if key == "track_tension_sprocket":
            axis.plot(t, result["track_tension_idler"] * scale, lw=1.0, ls="--", color="C0")
        axis.set_ylabel(label)
        axis.grid(alpha=0.3)
    if linear is not None:
        axes[0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[0].set_title(title)
    axes[-1].set_xlabel("time (s)")
    save_figure(figure, path)


def _draw(axis, result, i, course):
    pins = result["pins"][i]
    loop = np.vstack([pins, pins[:1]])
    axis.plot(loop[:, 0], loop[:, 1], "-", color="0.2", lw=1.0)
    axis.plot(pins[:, 0], pins[:, 1], ".", color="0.2", ms=2)
    for centre in result["wheels"][i]:
        axis.add_patch(_circle(centre, lay.WHEEL_RADIUS, "C0"))
    axis.add_patch(_circle(result["idler"][i], lay.IDLER_PIN_RADIUS - lay.LINK_INNER, "C2"))
    x = np.linspace(pins[:, 0].min() - 1.0, pins[:, 0].max() + 1.0, 400)
    axis.fill_between(x, course.height(x), -0.3, color="0.85")
    axis.set_aspect("equal")


def _circle(centre, radius, colour):
    from matplotlib.patches import Circle
    return Circle(centre, radius, fill=False, color=colour, lw=1.0)


def plot_shapes(path, result, course, count=4):
    from plotting import plt, save_figure

    t = result["time"]
    instants = np.linspace(0, len(t) - 1, count).astype(int)
    figure, axes = plt.subplots(count, 1, figsize=(10, 2.6 * count))
    for axis, i in zip(axes, instants):
        _draw(axis, result, i, course)
        axis.set_title(f"t = {t[i]:.3f} s", fontsize=9)
        axis.set_ylabel("height (m)")
    axes[-1].set_xlabel("distance along the course (m)")
    save_figure(figure, path)


def animate(path, result, course, frames=120):
    """A GIF of the track, the wheels and the ground (matplotlib's PillowWriter)."""
    from matplotlib.animation import FuncAnimation, PillowWriter
    from plotting import plt

    t = result["time"]
    picks = np.unique(np.linspace(0, len(t) - 1, min(frames, len(t))).astype(int))
    figure, axis = plt.subplots(figsize=(9, 3.2))

    def frame(n):
        axis.clear()
        i = picks[n]
        _draw(axis, result, i, course)
        centre = result["hull_x"][i]
        axis.set_xlim(centre - 4.0, centre + 4.0)
        axis.set_ylim(-0.3, 1.6)
        axis.set_title(f"t = {t[i]:.3f} s")

    span = t[-1] - t[0]
    fps = max(1, min(25, round(len(picks) / max(span, 1e-9))))
    FuncAnimation(figure, frame, frames=len(picks)).save(path, writer=PillowWriter(fps=fps))
    plt.close(figure)
