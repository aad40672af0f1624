"""Generates contact_shape_reference.csv: shapely's verdict on disc-disc and disc-rectangle pairs.

SocNavGym 0.1.1 decides every contact with shapely (envs/utils/object.py `collides`): a disc is
`Point((x, y)).buffer(r)` (GEOS's default quad_segs = 16, a regular 64-gon inscribed in the
circle, vertices at angles k*pi/32), a table, laptop or wall the polygon of
`get_coordinates_of_rotated_rectangle`, and the answer `intersects` (touching counts). This file
pins that verdict for pairs sampled near the contact threshold, where exact discs and 64-gons
disagree, plus random near and far pairs; tests/suite/step/contacts/shape.rs checks socnav's
`contact_shape = "polygon64"` against it.

Reference library: PyPI `shapely` 2.x (2.2.0 with GEOS 3.14.1 made the committed file).
Run: `python gen_contact_shape_reference.py > contact_shape_reference.csv`.

Every input is a float32 value printed with %.9g, so that socnav reads back exactly the numbers
shapely was given (as float64). Lines:
  disc,ax,ay,ar,bx,by,br,intersects
  rect,x,y,r,rx,ry,theta,length,width,intersects
where `rect` is a disc (x, y, r) and the rectangle centred at (rx, ry) with heading theta (rad),
`length` along its local x axis and `width` along local y; `intersects` is 0 or 1.
"""

import math
import random
import struct

from shapely.geometry import Point, Polygon

SEED = 64
PAIRS_PER_KIND = 320
# Near-threshold pairs sit at t x the contact distance, t drawn from this range: it spans the
# 64-gon's inset (cos(pi/64) = 0.99880) and a little more on both sides.
NEAR_T = (0.9980, 1.0005)


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


def g(x):
    return "%.9g" % x


def rotated_rectangle(x, y, orientation, length, width):
    """0.1.1's `get_coordinates_of_rotated_rectangle` (envs/utils/utils.py), with math for np."""
    c, s = math.cos(orientation), math.sin(orientation)
    return [
        (x + length / 2 * c - width / 2 * s, y + length / 2 * s + width / 2 * c),
        (x - length / 2 * c - width / 2 * s, y - length / 2 * s + width / 2 * c),
        (x - length / 2 * c + width / 2 * s, y - length / 2 * s - width / 2 * c),
        (x + length / 2 * c + width / 2 * s, y + length / 2 * s - width / 2 * c),
    ]


def disc(x, y, r):
    return Point((x, y)).buffer(r)


def radius(rng):
    # The step's radii: robot 0.25 m, humans 0.36 m (diameter 0.72), plants 0.4 m, and others.
    return f32(rng.choice([0.25, 0.36, 0.4, rng.uniform(0.1, 0.6)]))


def disc_pairs(rng):
    for n in range(PAIRS_PER_KIND):
        ax, ay = f32(rng.uniform(-8, 8)), f32(rng.uniform(-8, 8))
        ar, br = radius(rng), radius(rng)
        if n % 3 == 2:
            t = rng.uniform(0.0, 2.0)  # anywhere, near or far
        else:
            t = rng.uniform(*NEAR_T)
        # A third of the near pairs along the exact vertex or edge-normal directions.
        if n % 6 == 0:
            phi = rng.randrange(64) * math.pi / 32
        elif n % 6 == 1:
            phi = (rng.randrange(64) + 0.5) * math.pi / 32
        else:
            phi = rng.uniform(0.0, 2 * math.pi)
        dist = t * (ar + br)
        bx, by = f32(ax + dist * math.cos(phi)), f32(ay + dist * math.sin(phi))
        hit = disc(ax, ay, ar).intersects(disc(bx, by, br))
        print(",".join(["disc", g(ax), g(ay), g(ar), g(bx), g(by), g(br), str(int(hit))]))


def rect_pairs(rng):
    for n in range(PAIRS_PER_KIND):
        rx, ry = f32(rng.uniform(-8, 8)), f32(rng.uniform(-8, 8))
        theta = f32(rng.uniform(-math.pi, math.pi))
        length, width = f32(rng.uniform(0.1, 3.0)), f32(rng.uniform(0.05, 1.5))
        r = radius(rng)
        c, s = math.cos(theta), math.sin(theta)
        hl, hw = length / 2, width / 2
        if n % 3 == 2:
            # Anywhere around the rectangle, near or far.
            lx = rng.uniform(-hl - 2 * r, hl + 2 * r)
            ly = rng.uniform(-hw - 2 * r, hw + 2 * r)
        else:
            t = rng.uniform(*NEAR_T)
            sx, sy = rng.choice([-1, 1]), rng.choice([-1, 1])
            if n % 3 == 0:
                # Off a corner, in the corner's quarter of directions.
                phi = rng.uniform(0.0, math.pi / 2)
                lx = sx * (hl + t * r * math.cos(phi))
                ly = sy * (hw + t * r * math.sin(phi))
            elif rng.random() < 0.5:
                lx, ly = sx * (hl + t * r), rng.uniform(-hw, hw)
            else:
                lx, ly = rng.uniform(-hl, hl), sy * (hw + t * r)
        x, y = f32(rx + lx * c - ly * s), f32(ry + lx * s + ly * c)
        rect = Polygon(rotated_rectangle(rx, ry, theta, length, width))
        hit = disc(x, y, r).intersects(rect)
        row = ["rect", g(x), g(y), g(r), g(rx), g(ry), g(theta), g(length), g(width)]
        print(",".join(row + [str(int(hit))]))


def main():
    rng = random.Random(SEED)
    disc_pairs(rng)
    rect_pairs(rng)


if __name__ == "__main__":
    main()
