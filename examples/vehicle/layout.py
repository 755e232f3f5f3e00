"""The vehicle's values and the track loop's geometry at the static point.

Frame: x forward, y up, origin on the ground under the hull's centre of gravity at t = 0;
angles counter-clockwise. Values cited by thesis section; the rest are assumed, each with
its reason in docs/vehicle.md.
"""

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

GRAVITY = 9.81
VEHICLE_MASS = 27000.0  # kg, section 5.1.1 ("approximately 27 tonne")
SIDE_MASS = VEHICLE_MASS / 2  # one side's share: the model is the pitch plane of one side
STATIONS = 6  # road-wheel stations per side, section 1.1 / 9.0
DAMPED_STATIONS = (1, 2, 6)  # section 9.0: rotary dampers at stations 1, 2 and 6
STATION_SPACING = 0.72  # m between stations (assumed)
ARM_LENGTH = 0.4  # m, section 9.0 / 9.1
ARM_STATIC_ANGLE = math.radians(30.0)  # trailing, below horizontal (assumed)
ARM_MASS = 40.0  # kg (assumed, as the station example)
WHEEL_MASS = 80.0  # kg, two half-wheels (assumed, as the station example)
WHEEL_RADIUS = 0.613 / 2  # m, section 5.1.1
TYRE_RUBBER = (0.613 - 0.538) / 2  # m, the tyre's thickness, section 5.1.1: 37.5 mm
TYRES_PER_WHEEL = 2  # two half-wheels, one RoadWheelTyre instance each (section 5.1.1)
TORSION_BAR_STIFFNESS = 15000.0  # N.m/rad (assumed, as the station example)
LINK_PITCH = 0.15  # m (the project's track pitch; not printed in the thesis)
LINK_MASS = 15.0  # kg (assumed, as the track-span example)
LINK_INERTIA = LINK_MASS * (LINK_PITCH ** 2 + 0.06 ** 2) / 12
LINK_INNER = 0.03  # m from the pin line to the face the wheels run on (assumed)
LINK_OUTER = 0.03  # m from the pin line to the ground face (assumed)
TRACK_TENSION = 13e3  # N, section 5.1.2 ("tensioned to approximately 13kN")
# Section 5.1.2: the bush twists up to about 23 deg from its 10 deg live angle passing the
# sprocket and idler; a joint bends 360/N deg on an N-tooth wheel: 11 teeth give 22.7 deg.
SPROCKET_TEETH = 11
SPROCKET_PITCH_RADIUS = LINK_PITCH / (2 * math.sin(math.pi / SPROCKET_TEETH))  # 0.266 m
IDLER_PIN_RADIUS = SPROCKET_PITCH_RADIUS  # the pin circle round the idler (assumed equal)
ROLLER_PIN_RADIUS = 0.13  # m, the single support roller, section 1.1 (size assumed)
SPROCKET_AHEAD = 0.80  # m, sprocket centre ahead of station 1 (assumed)
SPROCKET_HEIGHT = 0.80  # m above the ground (assumed)
IDLER_BEHIND = 0.70  # m, idler centre behind station 6 (first guess; closes the loop)
IDLER_HEIGHT = 0.62  # m (assumed)
BEND_RADIUS = 0.01  # m, the path's turn where the track leaves the ground run (a sharp bend)
BEND_CLEARANCE = 0.06  # m, beyond where the rising link would touch the end wheels' tyres
ROLLER_LIFT = 0.01  # m, the roller's top above the straight top run (assumed)
CRANK_LENGTH = 0.25  # m, idler crank, pivot ahead of and above the idler (assumed)
CRANK_ANGLE = math.radians(30.0)  # the crank's angle above horizontal (assumed)
CRANK_MASS = 60.0  # kg, idler wheel and crank (assumed)
TENSIONER_STIFFNESS = 4e4  # N.m/rad at the crank (assumed)
HULL_CG_HEIGHT = 1.1  # m above the ground (assumed)
HULL_RADIUS_OF_GYRATION = 1.8  # m, pitch (assumed)
SEAT = (2.2, 0.3)  # m, the driver's seat from the CG (front left of the hull; assumed)


@dataclass
class Arc:
    centre: np.ndarray
    radius: float
    start: float  # angle where the path arrives
    sweep: float  # counter-clockwise, >= 0

    @property
    def length(self):
        return self.radius * self.sweep

    def point(self, s):
        angle = self.start + s / self.radius
        return self.centre + self.radius * np.array([math.cos(angle), math.sin(angle)])


@dataclass
class Line:
    start: np.ndarray
    end: np.ndarray

    @property
    def length(self):
        return float(np.hypot(*(self.end - self.start)))

    def point(self, s):
        return self.start + (self.end - self.start) * (s / self.length)


def outer_tangent(c1, r1, c2, r2):
    """Tangent points from circle 1 to circle 2 with both on the left of the travel (a
    loop run counter-clockwise round the circles)."""
    d = c2 - c1
    distance = math.hypot(*d)
    u = d / distance
    right = np.array([u[1], -u[0]])
    sine = (r1 - r2) / distance
    normal = sine * u + math.sqrt(1 - sine ** 2) * right
    return c1 + r1 * normal, c2 + r2 * normal


@dataclass
class Path:
    """A closed loop of lines and arcs, counter-clockwise, by arc length."""
    pieces: list = field(default_factory=list)

    @property
    def length(self):
        return sum(p.length for p in self.pieces)

    def point(self, s):
        s = s % self.length
        for piece in self.pieces:
            if s <= piece.length:
                return piece.point(s)
            s -= piece.length
        return self.pieces[-1].point(self.pieces[-1].length)


def loop_path(circles):
    """The loop round circles [(centre, radius)] given counter-clockwise."""
    n = len(circles)
    tangents = [outer_tangent(*circles[i], *circles[(i + 1) % n]) for i in range(n)]
    pieces = []
    for i in range(n):
        centre, radius = circles[(i + 1) % n]
        arrive, leave = tangents[i][1], tangents[(i + 1) % n][0]
        pieces.append(Line(*tangents[i]))
        a0 = math.atan2(*(arrive - centre)[::-1])
        a1 = math.atan2(*(leave - centre)[::-1])
        pieces.append(Arc(centre, radius, a0, (a1 - a0) % (2 * math.pi)))
    return Path(pieces)


def walk_pins(path, chord, count):
    """`count` pins along the path, each `chord` from the last (on a straight piece and
    round a circle alike); returns the pins and where the next one would land (its arc
    length), which closes the loop when it equals the path's length."""
    s, pins = 0.0, [path.point(0.0)]
    for _ in range(count):
        start = path.point(s)
        s = brentq(lambda t: np.hypot(*(path.point(t) - start)) - chord, s + 0.5 * chord,
                   s + 1.5 * chord, xtol=1e-13)
        pins.append(path.point(s))
    return np.array(pins[:-1]), s


class Layout:
    """Where everything is at the static point: stations, sprocket, idler, roller, and
    the pins of a closed loop of links whose joints are all `chord` apart (the pitch plus
    the radial bushes' deflection under the tension)."""

    def __init__(self, static_compression, chord):
        self.static_compression = static_compression
        # Stations numbered 1 (front) to 6; the CG above the middle of them.
        self.station_x = np.array([(STATIONS + 1) / 2 - i for i in range(1, STATIONS + 1)]) \
            * STATION_SPACING
        wheel_y = LINK_OUTER + LINK_INNER + WHEEL_RADIUS - static_compression
        self.wheel_centres = np.array([[x, wheel_y] for x in self.station_x])
        self.pivots = self.wheel_centres + ARM_LENGTH * np.array(
            [math.cos(ARM_STATIC_ANGLE), math.sin(ARM_STATIC_ANGLE)])
        self.sprocket = np.array([self.station_x[0] + SPROCKET_AHEAD, SPROCKET_HEIGHT])
        self.cg = np.array([0.0, HULL_CG_HEIGHT])
        self.chord = chord
        guess = self._loop(self.station_x[-1] - IDLER_BEHIND)[0]
        self.links = int(guess.length / chord)

        def residual(idler_x):
            path = self._loop(idler_x)[0]
            return walk_pins(path, chord, self.links)[1] - path.length

        x0 = self.station_x[-1] - IDLER_BEHIND
        idler_x = brentq(residual, x0 - 0.3, x0 + 0.3, xtol=1e-12)
        self.path, self.idler, self.roller = self._loop(idler_x)
        self.pins, _ = walk_pins(self.path, chord, self.links)
        self.crank_pivot = self.idler + CRANK_LENGTH * np.array(
            [math.cos(CRANK_ANGLE), math.sin(CRANK_ANGLE)])

    def idler_pull(self):
        """Unit vectors along the two spans leaving the idler (to the roller and to the
        last road wheel): the track pulls the idler along their sum."""
        to_roller, to_wheel = self.path.pieces[6], self.path.pieces[8]
        a = to_roller.start - to_roller.end
        b = to_wheel.end - to_wheel.start
        return a / np.hypot(*a), b / np.hypot(*b)

    def arc(self, index):
        """The loop's arc round circle `index` (0 the bend behind the last wheel, 1 the bend
        ahead of the first, 2 sprocket, 3 roller, 4 idler)."""
        return self.path.pieces[2 * ((index - 1) % 5) + 1]

    def _loop(self, idler_x):
        idler = np.array([idler_x, IDLER_HEIGHT])
        top = loop_path([(self.sprocket, SPROCKET_PITCH_RADIUS), (idler, IDLER_PIN_RADIUS)])
        a, b = top.pieces[0].start, top.pieces[0].end  # the top run, sprocket to idler
        roller_x = 0.5 * (self.station_x[2] + self.station_x[3])
        line_y = a[1] + (b[1] - a[1]) * (roller_x - a[0]) / (b[0] - a[0])
        roller = np.array([roller_x, line_y + ROLLER_LIFT - ROLLER_PIN_RADIUS])
        # The track leaves the ground run at a bend ahead of the first wheel and behind the
        # last (it does not wrap them): far enough out that the rising link clears the tyre
        # (a bend of angle b at x from the wheel's centre clears it for x > rho tan(b / 2),
        # rho the wheel centre's height above the pin line).
        rho = self.wheel_centres[0][1] - LINK_OUTER
        offsets = [0.15, 0.15]
        for _ in range(3):
            bends = [np.array([self.station_x[-1] - offsets[1], LINK_OUTER + BEND_RADIUS]),
                     np.array([self.station_x[0] + offsets[0], LINK_OUTER + BEND_RADIUS])]
            circles = [(bends[0], BEND_RADIUS), (bends[1], BEND_RADIUS),
                       (self.sprocket, SPROCKET_PITCH_RADIUS), (roller, ROLLER_PIN_RADIUS),
                       (idler, IDLER_PIN_RADIUS)]
            path = loop_path(circles)
            rising = [path.pieces[8], path.pieces[2]]  # down from the idler, up to the sprocket
            angles = [abs(math.atan2(*(line.end - line.start)[::-1])) for line in rising]
            offsets = [rho * math.tan(0.5 * min(angles[1], math.pi - angles[1])) + BEND_CLEARANCE,
                       rho * math.tan(0.5 * min(angles[0], math.pi - angles[0])) + BEND_CLEARANCE]
        self.bends = bends
        # start the pins mid-way along the bottom run
        return _Shifted(path, path.pieces[0].length / 2), idler, roller


class _Shifted:
    """A path whose arc length starts `offset` along another."""

    def __init__(self, path, offset):
        self.path, self.offset = path, offset
        self.pieces = path.pieces

    @property
    def length(self):
        return self.path.length

    def point(self, s):
        return self.path.point(s + self.offset)


def side_masses(links):
    """(hull sprung mass, its pitch inertia) of one side: its share of the vehicle less
    the track, the wheels, the arms and the idler with its crank."""
    unsprung = links * LINK_MASS + STATIONS * (WHEEL_MASS + ARM_MASS) + CRANK_MASS
    hull = SIDE_MASS - unsprung
    return hull, hull * HULL_RADIUS_OF_GYRATION ** 2
