"""Generates ref/orca_hard/: RVO2 one-step cases that the published one-step set does not hold,
in its format (the five `rvo2_onestep_*.csv` files of ref/orca_sfm, README there), so that the
one-step reference tests read them as they read that set (`SOCNAV_REF_DIR=tests/data/ref/orca_hard`,
and the suite runs them from here too).

The cases, 8 of each kind in turn (case % 8 picks the variant):
  grid       agents on an integer grid (exactly tied distances; a neighbour cut inside a tie)
  repeated   polygons with a repeated vertex (a zero-length edge: RVO2's unit direction is NaN)
  collinear  polygons with collinear edges (three vertices on a line)
  vertex     agents exactly on obstacle vertices and edges, and on each other's tie circles

Reference library: PyPI `pyrvo==0.4.3` (bundles RVO2 2.0.3; `pip install --no-deps pyrvo==0.4.3`).
Run from tests/data: `python gen_orca_onestep_hard.py ref/orca_hard`.
Values are float32 printed with %.9g (exact); non-finite values are printed as `nan`/`inf`.
"""

import csv
import math
import os
import sys

import pyrvo

from gen_orca_split_reference import Lcg, f32, g

CASES_PER_KIND = 8
DT = 0.25


def grid_case(rng, variant):
    """Agents on a grid of spacing 1 (or 0.5), some cells empty; every agent's nearest
    neighbours are exactly tied. max_neighbors 1..8 puts the cut inside a tie group."""
    spacing = 1.0 if variant % 2 == 0 else 0.5
    side = 3 + variant % 3
    agents = []
    for iy in range(side):
        for ix in range(side):
            if (ix * 7 + iy * 3 + variant) % 5 == 4:
                continue
            agents.append(((ix - side // 2) * spacing, (iy - side // 2) * spacing))
    params = dict(nd=f32(2.5 * spacing + variant * 0.25), max_nb=1 + variant, th=f32(2.0), tho=f32(2.0))
    return agents, [], params


def repeated_case(rng, variant):
    """A square with one vertex repeated (in the middle, or first == last), a triangle with
    a repeated vertex, and a two-vertex segment; agents scattered around them."""
    square = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
    k = variant % 4
    repeated = square[: k + 1] + [square[k]] + square[k + 1 :]
    if variant >= 4:
        repeated = square + [square[0]]  # the ring closes on a repeated vertex
    triangle = [(2.5, -0.5), (3.5, -0.5), (3.5, -0.5), (3.0, 0.5)]
    polygons = [repeated, triangle, [(-3.0, 2.0), (3.0, 2.0)]]
    agents = [(rng.uniform(-4, 4), rng.uniform(-3, 3)) for _ in range(10)]
    return agents, polygons, dict(nd=rng.uniform(3, 8), max_nb=1 + variant, th=rng.uniform(1, 4), tho=rng.uniform(1, 4))


def collinear_case(rng, variant):
    """A rectangle with extra vertices on its edges, a concave polygon with a straight run,
    and a segment collinear with an edge of the first."""
    rect = [(-2.0, -1.0), (0.0, -1.0), (2.0, -1.0), (2.0, 0.0), (2.0, 1.0), (-2.0, 1.0)]
    rect = rect[variant % len(rect) :] + rect[: variant % len(rect)]
    concave = [(3.0, -2.0), (5.0, -2.0), (5.0, 2.0), (4.0, 2.0), (4.0, 0.0), (4.0, -1.0), (3.0, -1.0)]
    polygons = [rect, concave, [(-5.0, -1.0), (-3.0, -1.0)]]
    agents = [(rng.uniform(-5, 6), rng.uniform(-3, 3)) for _ in range(10)]
    return agents, polygons, dict(nd=rng.uniform(3, 8), max_nb=1 + variant, th=rng.uniform(1, 4), tho=rng.uniform(1, 4))


def vertex_case(rng, variant):
    """Agents exactly on obstacle vertices, on edge midpoints and at a vertex's distance of
    their radius, beside a square and an L."""
    square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    ell = [(-4.0, -3.0), (-2.0, -3.0), (-2.0, -2.0), (-3.0, -2.0), (-3.0, 2.0), (-4.0, 2.0)]
    polygons = [square, ell]
    corners = [p for poly in polygons for p in poly]
    agents = [corners[(variant + k) % len(corners)] for k in range(3)]
    agents += [(0.5, 0.0), (-3.0, 0.0), (1.0 + 0.3, 1.0), (-2.0, -2.0 - 0.3)]
    agents += [(rng.uniform(-5, 3), rng.uniform(-4, 3)) for _ in range(3)]
    return agents, polygons, dict(nd=rng.uniform(3, 8), max_nb=1 + variant, th=rng.uniform(1, 4), tho=rng.uniform(1, 4))


KINDS = [grid_case, repeated_case, collinear_case, vertex_case]


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "ref/orca_hard"
    os.makedirs(out, exist_ok=True)
    files = {
        name: open(os.path.join(out, f"rvo2_onestep_{name}.csv"), "w", newline="")
        for name in ["agents", "lines", "neighbors", "obstacles", "obstacle_vertices_processed"]
    }
    w = {name: csv.writer(f, lineterminator="\n") for name, f in files.items()}
    w["agents"].writerow(
        "case,time_step,neighbor_dist,max_neighbors,time_horizon,time_horizon_obst,agent,radius,max_speed,"
        "px,py,vx,vy,pref_vx,pref_vy,new_vx,new_vy,new_px,new_py,n_lines,n_obst_neighbors,violated_lines,"
        "max_violation".split(",")
    )
    w["lines"].writerow("case,agent,line,point_x,point_y,dir_x,dir_y".split(","))
    w["neighbors"].writerow("case,agent,kind,rank,neighbor_id".split(","))
    w["obstacles"].writerow("case,obstacle,vertex,x,y".split(","))
    w["obstacle_vertices_processed"].writerow("case,vertex_id,x,y,next_id,prev_id".split(","))
    rng = Lcg(51)
    case = 0
    for kind in KINDS:
        for variant in range(CASES_PER_KIND):
            positions, polygons, params = kind(rng, variant)
            run_case(w, case, rng, positions, polygons, params)
            case += 1
    for f in files.values():
        f.close()


def run_case(w, case, rng, positions, polygons, params):
    sim = pyrvo.RVOSimulator()
    sim.set_time_step(DT)
    for j, poly in enumerate(polygons):
        for k, (x, y) in enumerate(poly):
            w["obstacles"].writerow([case, j, k, g(f32(x)), g(f32(y))])
        sim.add_obstacle([(f32(x), f32(y)) for x, y in poly])
    sim.process_obstacles()
    for i in range(sim.get_num_obstacle_vertices()):
        p = sim.get_obstacle_vertex(i)
        w["obstacle_vertices_processed"].writerow(
            [case, i, g(p.x), g(p.y), sim.get_next_obstacle_vertex(i), sim.get_prev_obstacle_vertex(i)]
        )
    rows = []
    for i, pos in enumerate(positions):
        pos = (f32(pos[0]), f32(pos[1]))
        vel = (rng.uniform(-1, 1), rng.uniform(-1, 1))
        pref = (rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5))
        radius = f32(0.3) if i % 2 == 0 else rng.uniform(0.2, 0.45)
        max_speed = rng.uniform(0.5, 1.5)
        a = sim.add_agent(pos, params["nd"], params["max_nb"], params["th"], params["tho"], radius, max_speed, vel)
        sim.set_agent_pref_velocity(a, pref)
        rows.append((pos, vel, pref, radius, max_speed))
    sim.do_step()
    for i, (pos, vel, pref, radius, max_speed) in enumerate(rows):
        for k in range(sim.get_agent_num_obstacle_neighbors(i)):
            w["neighbors"].writerow([case, i, "obstacle_vertex", k, sim.get_agent_obstacle_neighbor(i, k)])
        for k in range(sim.get_agent_num_agent_neighbors(i)):
            w["neighbors"].writerow([case, i, "agent", k, sim.get_agent_agent_neighbor(i, k)])
        v = sim.get_agent_velocity(i)
        n_lines = sim.get_agent_num_orca_lines(i)
        violated, worst = 0, 0.0
        for k in range(n_lines):
            (dx, dy), (px, py) = sim.get_agent_orca_line(i, k)  # pyrvo returns (direction, point)
            w["lines"].writerow([case, i, k, g(px), g(py), g(dx), g(dy)])
            # The feasible side is det(dir, point - v) <= 0 (README); NaN lines violate nothing.
            violation = dx * (py - v.y) - dy * (px - v.x)
            if violation > 1e-4:
                violated += 1
                worst = max(worst, violation)
        p = sim.get_agent_position(i)
        w["agents"].writerow(
            [case, g(DT), g(params["nd"]), params["max_nb"], g(params["th"]), g(params["tho"]), i, g(radius),
             g(max_speed), g(pos[0]), g(pos[1]), g(vel[0]), g(vel[1]), g(pref[0]), g(pref[1]), g(v.x), g(v.y),
             g(p.x), g(p.y), n_lines, sim.get_agent_num_obstacle_neighbors(i), violated, g(worst)]
        )


if __name__ == "__main__":
    main()
