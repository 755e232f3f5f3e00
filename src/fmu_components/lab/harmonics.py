"""First-harmonic analysis of a steady periodic force-deflection record.

What an engineer reads off a sine test on an elastomer mount (ISO 10846, ASTM D5992), from
the last whole cycles of a record that has reached its periodic steady state:

* dynamic stiffness |K*| = first-harmonic force amplitude / first-harmonic deflection
  amplitude;
* loss angle delta = phase of the force's first harmonic minus the deflection's;
* energy per cycle, the loop area: the integral of F dx around one cycle (positive for a
  part that dissipates);
* secant stiffness (F(x_max) - F(x_min)) / (x_max - x_min), the slope of the line through
  the loop's two tips.

From |K*| and delta follow the storage and loss stiffness K' = |K*| cos(delta) and
K'' = |K*| sin(delta), and the equivalent viscous damping c_eq = K'' / omega: the linear
spring and dashpot in parallel (Kelvin element) with the same first harmonic. For the
rotary damper these are its equivalent stiffness and damping.

Uniformly sampled cycles (a whole number of samples per cycle) are analysed by the discrete
Fourier transform, exact for a band-limited record; any other sampling by the trapezoidal
rule over the window, its start interpolated.

The torsion bush's dual sine (section 5.8) has loops within its loop: ``secondary_loop_areas``
gives the energy each cycle of its small, fast motion dissipates.
"""

import math
from dataclasses import dataclass

import numpy as np

from .signals import DUAL_SINE, DUAL_SINE_SHOWN, DUAL_SINE_STEP


@dataclass(frozen=True)
class HarmonicResult:
    dynamic_stiffness: float  # |K*|, force unit per deflection unit
    loss_angle_deg: float  # phase of the force's first harmonic against the deflection's
    energy_per_cycle: float  # loop area, integral of F dx over one cycle
    secant_stiffness: float  # (F(x_max) - F(x_min)) / (x_max - x_min)
    frequency: float  # Hz
    deflection_amplitude: float  # first-harmonic amplitude of the deflection
    force_amplitude: float  # first-harmonic amplitude of the force
    mean_deflection: float
    mean_force: float
    cycles: int  # whole cycles analysed

    @property
    def storage_stiffness(self):
        """K' = |K*| cos(delta): the equivalent (in-phase) stiffness."""
        return self.dynamic_stiffness * math.cos(math.radians(self.loss_angle_deg))

    @property
    def loss_stiffness(self):
        """K'' = |K*| sin(delta)."""
        return self.dynamic_stiffness * math.sin(math.radians(self.loss_angle_deg))

    @property
    def equivalent_stiffness(self):
        return self.storage_stiffness

    @property
    def equivalent_damping(self):
        """c_eq = |K*| sin(delta) / omega: the viscous damping with the same first harmonic
        (and the same energy per cycle, pi c_eq omega A^2, for a pure sine deflection)."""
        return self.loss_stiffness / (2.0 * math.pi * self.frequency)

    def change_from(self, other):
        """The largest relative change of |K*|, the loss angle (relative to the larger of
        1 degree and its value) and the energy per cycle against another result: how far a
        record still is from its periodic steady state."""
        def relative(a, b, floor):
            return abs(a - b) / max(abs(a), abs(b), floor)
        return max(relative(self.dynamic_stiffness, other.dynamic_stiffness, 1e-300),
                   relative(self.loss_angle_deg, other.loss_angle_deg, 1.0),
                   relative(self.energy_per_cycle, other.energy_per_cycle,
                            1e-12 * self.force_amplitude * self.deflection_amplitude))


class HarmonicError(ValueError):
    """The record cannot give a first harmonic (too short, not finite, no motion)."""


def first_harmonic(times, deflection, force, frequency, cycles=None):
    """The first-harmonic result of the last `cycles` whole cycles of the record (default:
    as many whole cycles as it holds). times: increasing, s; frequency: Hz."""
    t = np.asarray(times, dtype=float)
    x = np.asarray(deflection, dtype=float)
    f = np.asarray(force, dtype=float)
    if not (t.shape == x.shape == f.shape and t.ndim == 1):
        raise HarmonicError("times, deflection and force must be one-dimensional and of one length")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x)) and np.all(np.isfinite(f))):
        raise HarmonicError("the record holds a value that is not a finite number")
    if not frequency > 0.0:
        raise HarmonicError(f"frequency {frequency!r} Hz must be positive")
    if len(t) < 3 or np.any(np.diff(t) <= 0.0):
        raise HarmonicError("times must increase, with at least three samples")
    period = 1.0 / frequency
    span = t[-1] - t[0]
    available = int(math.floor(span / period * (1.0 + 1e-9)))
    if available < 1:
        raise HarmonicError(f"the record spans {span:.6g} s, less than one cycle of "
                            f"{period:.6g} s")
    cycles = available if cycles is None else int(cycles)
    if not 1 <= cycles <= available:
        raise HarmonicError(f"asked for {cycles} cycles; the record holds {available}")
    start = t[-1] - cycles * period
    window = _uniform_window(t, start)
    if window is not None:
        tw, xw, fw = t[window:], x[window:], f[window:]
        x1, fourier_x = _dft_first(xw[:-1], cycles)
        f1, fourier_f = _dft_first(fw[:-1], cycles)
        # loop area of one cycle: the integral of F x' dt over it is pi * sum over the
        # harmonics n of n (A_n b_n - B_n a_n), exact for a band-limited record.
        n = np.arange(len(fourier_x))
        energy = float(np.pi * np.sum(n * _cross(fourier_x, fourier_f)))
        mean_x, mean_f = float(np.mean(xw[:-1])), float(np.mean(fw[:-1]))
    else:
        tw, xw, fw = _trimmed(t, x, f, start)
        omega = 2.0 * math.pi * frequency
        duration = tw[-1] - tw[0]
        phase = np.exp(-1j * omega * (tw - tw[0]))
        x1 = 2.0 * np.trapezoid(xw * phase, tw) / duration
        f1 = 2.0 * np.trapezoid(fw * phase, tw) / duration
        energy = float(np.sum(0.5 * (fw[1:] + fw[:-1]) * np.diff(xw))) / cycles
        mean_x = float(np.trapezoid(xw, tw) / duration)
        mean_f = float(np.trapezoid(fw, tw) / duration)
    amplitude_x, amplitude_f = abs(x1), abs(f1)
    if not amplitude_x > 0.0:
        raise HarmonicError("the deflection has no first harmonic at this frequency")
    loss_angle = math.degrees(math.remainder(np.angle(f1) - np.angle(x1), 2.0 * math.pi))
    # the loop's tips in the last cycle
    last = tw >= tw[-1] - period * (1.0 + 1e-9)
    xl, fl = xw[last], fw[last]
    top, bottom = int(np.argmax(xl)), int(np.argmin(xl))
    secant = float((fl[top] - fl[bottom]) / (xl[top] - xl[bottom]))
    return HarmonicResult(
        dynamic_stiffness=float(amplitude_f / amplitude_x), loss_angle_deg=loss_angle,
        energy_per_cycle=energy, secant_stiffness=secant, frequency=float(frequency),
        deflection_amplitude=float(amplitude_x), force_amplitude=float(amplitude_f),
        mean_deflection=mean_x, mean_force=mean_f, cycles=cycles)


def _uniform_window(t, start):
    """Index of the sample at `start` if the record is uniformly sampled and the window
    [start, t_end] is a whole number of its samples, else None."""
    steps = np.diff(t)
    step = (t[-1] - t[0]) / (len(t) - 1)
    if np.max(np.abs(steps - step)) > 1e-9 * step:
        return None
    count = (t[-1] - start) / step
    if abs(count - round(count)) > 1e-6 or round(count) < 4:
        return None
    return len(t) - 1 - int(round(count))


def _dft_first(values, cycles):
    """(complex first-harmonic amplitude at the analysed frequency, the one-sided complex
    amplitudes of every harmonic of it) of samples spanning `cycles` whole cycles."""
    spectrum = np.fft.rfft(values) / len(values)
    harmonics = spectrum[::cycles].copy()  # bins 0, cycles, 2 cycles, ...: the harmonics
    harmonics[1:] *= 2.0
    if len(values) % 2 == 0 and (len(values) // 2) % cycles == 0:
        harmonics[-1] /= 2.0  # the Nyquist bin appears once
    # the sign: rfft uses exp(-i...), so bin 1 is (a1 - i b1)/2 for a1 cos + b1 sin
    return harmonics[1], harmonics


def _cross(fourier_x, fourier_f):
    """n-independent factor of each harmonic's loop area: A_n b_n - B_n a_n, with
    a - i b the complex amplitude of a cos + b sin."""
    a, b = np.real(fourier_x), -np.imag(fourier_x)
    fa, fb = np.real(fourier_f), -np.imag(fourier_f)
    return fa * b - fb * a


def _trimmed(t, x, f, start):
    """The samples from `start` on, the first one interpolated at `start`."""
    first = int(np.searchsorted(t, start, side="right"))
    head = (start, float(np.interp(start, t, x)), float(np.interp(start, t, f)))
    return (np.concatenate(([head[0]], t[first:])), np.concatenate(([head[1]], x[first:])),
            np.concatenate(([head[2]], f[first:])))


def secondary_loop_areas(times, force, start=DUAL_SINE_SHOWN):
    """The energy the 1.5 Hz motion of the dual sine dissipates in each of its cycles from
    `start`: the integral of T dx2 over the cycle, x2 the 1.5 Hz component alone (it closes
    each cycle; the 0.1 Hz motion does not). It is the area of the small loops the measured
    response encloses (Fig. 5.8-1): near zero where the small motion meets a stiffness alone."""
    amplitude, frequency = DUAL_SINE[1][1]
    per_cycle = int(round(1.0 / (frequency * DUAL_SINE_STEP)))
    small = amplitude * np.sin(2 * math.pi * frequency * times)
    first = int(np.searchsorted(times, start))
    areas = []
    while first + per_cycle <= len(times) - 1:
        x, f = small[first:first + per_cycle + 1], force[first:first + per_cycle + 1]
        areas.append(float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x))))
        first += per_cycle
    return np.array(areas)
