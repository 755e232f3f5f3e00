"""Small numpy helpers of the contacts' numpy kernel (contacts.py): the planar cross
product, a rotation, the smoothstep (contacts.c has their C twins)."""

import math

import numpy as np


def cross(omega, r):
    """omega (scalar, about z) x r (n x 2)."""
    return np.stack([-omega * r[..., 1], omega * r[..., 0]], axis=-1)


def smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def smoothstep_derivatives(x):
    """The smoothstep and its first and second derivatives."""
    inside = (x > 0.0) & (x < 1.0)
    return (smoothstep(x), np.where(inside, 6.0 * x * (1.0 - x), 0.0),
            np.where(inside, 6.0 - 12.0 * x, 0.0))


def rotate(angle, r):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * r[0] - s * r[1], s * r[0] + c * r[1]])
