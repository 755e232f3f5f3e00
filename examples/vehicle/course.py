"""The courses: ground height against distance x along the ground (m; x = 0 under the
hull's centre of gravity at t = 0). Every course is flat up to `start` ahead of the
sprocket, so a run begins at the static point."""

import math

import numpy as np

# ISO 8608:2016 roughness classes: displacement PSD Gd(n0) at n0 = 0.1 cycle/m, in m^3,
# the geometric mean of each class (A 16e-6, each next class four times the last), w = 2.
ISO8608_GD = {name: 16e-6 * 4 ** i for i, name in enumerate("ABCDEFGH")}
ISO8608_N0 = 0.1  # cycle/m
# m added to a course's bound on its height (Course.ceiling): the rounding of its sums
# (162 terms of at most 0.1 m: below 1e-14 m) many times over
CEILING_MARGIN = 1e-6


class Course:
    name = "flat"
    start = 1.0  # m, flat run ahead of the vehicle's front

    def __init__(self, front):
        self.front = front  # x of the track's front at t = 0

    def height(self, x):
        """Ground height at x (array in, array out)."""
        return np.zeros_like(np.asarray(x, dtype=float))

    def ceiling(self):
        """A height the course's height() never exceeds, m, margin included; math.inf (every
        height evaluated) for a course with no bound given: a class that changes height()
        gives its own ceiling."""
        return math.inf

    def under(self, x, face):
        """The course's height at x (array) where `face` (array, the heights of the links'
        ground faces there) is not above the ceiling: a face above it cannot meet the
        course (its contact's depth, the height less the face, is negative either way),
        and gets the ceiling instead of the height, not evaluated."""
        x, face = np.asarray(x, dtype=float), np.asarray(face, dtype=float)
        ceiling = self.ceiling()
        above = face > ceiling
        if not above.any():
            return self.height(x)
        z = np.full(x.shape, ceiling)
        z[~above] = self.height(x[~above])
        return z

    def along(self, x, length):
        """Distance past the flat start, in units of `length`."""
        return (np.asarray(x, dtype=float) - self.front - self.start) / length

    def describe(self):
        return "flat ground"


class Bump(Course):
    name = "bump"

    def __init__(self, front, height=0.08, length=1.0):
        super().__init__(front)
        self.bump_height, self.length = height, length

    def height(self, x):
        u = self.along(x, self.length)
        inside = (u > 0.0) & (u < 1.0)
        return np.where(inside, 0.5 * self.bump_height * (1 - np.cos(2 * math.pi * u)), 0.0)

    def ceiling(self):
        return max(self.bump_height, 0.0) + CEILING_MARGIN  # a dip's ceiling the flat

    def describe(self):
        return (f"single (1 - cos) bump, {self.bump_height * 1e3:g} mm high and "
                f"{self.length:g} m long, {self.start:g} m ahead of the track's front")

    def end(self):
        return self.front + self.start + self.length


class Sine(Course):
    name = "sine"

    def __init__(self, front, amplitude=0.03, wavelength=3.0):
        super().__init__(front)
        self.amplitude, self.wavelength = amplitude, wavelength

    def height(self, x):
        u = self.along(x, self.wavelength)
        return np.where(u > 0.0, self.amplitude * (1 - np.cos(2 * math.pi * u)), 0.0)

    def ceiling(self):
        return max(2 * self.amplitude, 0.0) + CEILING_MARGIN

    def describe(self):
        return (f"sine-wave course, {2 * self.amplitude * 1e3:g} mm peak to peak, "
                f"wavelength {self.wavelength:g} m, from {self.start:g} m ahead of the "
                f"track's front")


class RandomRoad(Course):
    """ISO 8608 road of class `roughness`: a sum of cosines with random phases whose
    amplitudes follow Gd(n) = Gd(n0) (n / n0)^-2 over wavelengths from 20 m down to
    `shortest` (the track's links bridge shorter ones), faded in over `fade` m."""
    name = "random"

    def __init__(self, front, roughness="C", shortest=0.6, fade=2.0, seed=8608):
        super().__init__(front)
        self.roughness, self.shortest, self.fade = roughness, shortest, fade
        gd0 = ISO8608_GD[roughness]
        dn = 0.01
        n = np.arange(1 / 20.0, 1 / shortest, dn)
        self.k = 2 * math.pi * n
        self.k_step = 2 * math.pi * dn  # the wave numbers are k[0] + j k_step
        self.amplitude = np.sqrt(2 * gd0 * (n / ISO8608_N0) ** -2 * dn)
        self.phase = np.random.default_rng(seed).uniform(0, 2 * math.pi, n.size)

    def height(self, x):
        x = np.asarray(x, dtype=float)
        u = x - self.front - self.start
        flat = np.atleast_1d(u)
        z = np.zeros_like(flat)
        on = flat > 0.0
        if on.any():
            # a cos(u k_j + phase) = Re(e^(i u k_j) a e^(i phase)), e^(i u k_j) turned term
            # by term from e^(i u k[0]) by e^(i u k_step) (one cosine and sine each a point)
            past = flat[on]
            turn = np.empty((past.size, self.k.size), dtype=complex)
            turn.real[:, 0], turn.imag[:, 0] = np.cos(past * self.k[0]), np.sin(past * self.k[0])
            turn.real[:, 1:] = np.cos(past * self.k_step)[:, None]
            turn.imag[:, 1:] = np.sin(past * self.k_step)[:, None]
            np.multiply.accumulate(turn, axis=1, out=turn)
            cosine, sine = self.weights()
            z[on] = (turn.real * cosine - turn.imag * sine).sum(axis=1)
            z[on] -= self.offset()  # starts at zero height
            z[on] *= np.minimum(flat[on] / self.fade, 1.0)
        return z.reshape(u.shape) if np.ndim(x) else float(z[0])

    def weights(self):
        """The terms' weights a cos(phase) and a sin(phase): a cos(u k + phase) is
        a cos(phase) cos(u k) - a sin(phase) sin(u k)."""
        return self.amplitude * np.cos(self.phase), self.amplitude * np.sin(self.phase)

    def offset(self):
        """The cosines' sum at the start, taken off the height."""
        return self.weights()[0].sum()

    def ceiling(self):
        """The cosines' sum is at most the sum of their amplitudes; less the offset, faded
        in (a factor of 0 to 1, over a height below that bound or negative)."""
        return max(np.abs(self.amplitude).sum() - self.offset(), 0.0) + CEILING_MARGIN

    def describe(self):
        return (f"random road, ISO 8608 class {self.roughness} (Gd(0.1 cycle/m) = "
                f"{ISO8608_GD[self.roughness] * 1e6:g}e-6 m^3, waviness 2), wavelengths "
                f"{self.shortest:g} to 20 m, seed fixed, from {self.start:g} m ahead of the "
                f"track's front")


COURSES = {course.name: course for course in (Bump, Sine, RandomRoad)}
