"""Generates orca_split_reference.txt: RVO2 doSteps on obstacles whose tree build splits edges.

The shared reference set never splits an edge, so these small cases pin the split rule
(vertex ids, positions, links) and the lines that read split vertices. Scene 0 is hand-made;
scenes 1.. have random star-shaped polygons (CCW, often concave). Reference library:
PyPI `pyrvo==0.4.3` (bundles RVO2 2.0.3; install with `pip install --no-deps pyrvo==0.4.3`).
Run: `python gen_orca_split_reference.py > orca_split_reference.txt`.

Output lines (values are float32 printed with %.9g):
  scene,s
  polygon,j,x0,y0,x1,y1,...
  vertex,id,x,y,next,prev
  agent,i,px,py,vx,vy,pref_vx,pref_vy,radius,max_speed,neighbor_dist,max_neighbors,th,tho
  obst,i,rank,vertex_id
  nb,i,rank,agent_id
  line,i,k,px,py,dx,dy
  new,i,vx,vy
"""

import math
import struct

import pyrvo


def f32(x):
    return struct.unpack("f", struct.pack("f", x))[0]


def g(x):
    return "%.9g" % x


class Lcg:
    def __init__(self, seed):
        self.s = seed

    def uniform(self, lo, hi):
        self.s = (self.s * 1664525 + 1013904223) % (1 << 32)
        return f32(lo + (hi - lo) * (self.s >> 8) / float(1 << 24))


POLYGONS = [
    [(-5.0, 0.5), (5.0, 0.5)],  # a segment whose line cuts the others
    [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)],  # CCW square
    [(3.0, -2.0), (4.0, -1.0), (3.0, 3.0), (2.5, -1.0)],  # concave quad
    [(-4.0, -3.0), (-2.0, -3.0), (-2.0, -2.0), (-3.0, -2.0), (-3.0, 2.0), (-4.0, 2.0)],  # L
]

DT = 0.25
NUM_RANDOM_SCENES = 12


def star_polygon(rng):
    cx, cy = rng.uniform(-5, 5), rng.uniform(-3, 3)
    n = 2 + int(rng.uniform(0, 5))
    angles = sorted(rng.uniform(0, 6.2831853) for _ in range(n))
    pts = []
    for a in angles:
        r = rng.uniform(0.3, 3.0)
        # Inputs only: rounded to f32 before RVO2 sees them, and printed exactly.
        pts.append((f32(cx + r * math.cos(a)), f32(cy + r * math.sin(a))))
    return pts


def main():
    rng = Lcg(2024)
    for scene in range(NUM_RANDOM_SCENES + 1):
        polygons = POLYGONS if scene == 0 else [star_polygon(rng) for _ in range(3)]
        run_scene(scene, polygons, rng, 24 if scene == 0 else 8)


def run_scene(scene, polygons, rng, num_agents):
    print("scene", scene, sep=",")
    sim = pyrvo.RVOSimulator()
    sim.set_time_step(DT)
    for j, poly in enumerate(polygons):
        print("polygon", j, *[g(c) for p in poly for c in p], sep=",")
        sim.add_obstacle([(x, y) for x, y in poly])
    sim.process_obstacles()
    for i in range(sim.get_num_obstacle_vertices()):
        p = sim.get_obstacle_vertex(i)
        print("vertex", i, g(p.x), g(p.y), sim.get_next_obstacle_vertex(i),
              sim.get_prev_obstacle_vertex(i), sep=",")

    agents = []
    for i in range(num_agents):
        pos = (rng.uniform(-6, 6), rng.uniform(-4, 4))
        vel = (rng.uniform(-1, 1), rng.uniform(-1, 1))
        pref = (rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5))
        radius = rng.uniform(0.2, 0.5)
        max_speed = rng.uniform(0.5, 1.5)
        nd = rng.uniform(2, 8)
        max_nb = 1 + (i % 10)
        th = rng.uniform(1, 5)
        tho = rng.uniform(1, 5)
        a = sim.add_agent(pos, nd, max_nb, th, tho, radius, max_speed, vel)
        sim.set_agent_pref_velocity(a, pref)
        agents.append((pos, vel, pref, radius, max_speed, nd, max_nb, th, tho))
        print("agent", i, *map(g, [*pos, *vel, *pref, radius, max_speed, nd]), max_nb, g(th),
              g(tho), sep=",")

    sim.do_step()
    for i in range(len(agents)):
        for k in range(sim.get_agent_num_obstacle_neighbors(i)):
            print("obst", i, k, sim.get_agent_obstacle_neighbor(i, k), sep=",")
        for k in range(sim.get_agent_num_agent_neighbors(i)):
            print("nb", i, k, sim.get_agent_agent_neighbor(i, k), sep=",")
        for k in range(sim.get_agent_num_orca_lines(i)):
            # pyrvo returns (direction, point).
            (dx, dy), (px, py) = sim.get_agent_orca_line(i, k)
            print("line", i, k, g(px), g(py), g(dx), g(dy), sep=",")
        v = sim.get_agent_velocity(i)
        print("new", i, g(v.x), g(v.y), sep=",")


if __name__ == "__main__":
    main()
