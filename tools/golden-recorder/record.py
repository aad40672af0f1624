#!/usr/bin/env python3
"""Record SocNavGym 0.1.1 episodes in the golden-episode format
(tests/data/golden/socnavgym/README.md of socnav).

  record.py CONFIG.yaml --seeds 20-39 --out DIR            # scripted policy (README section 1)
  record.py CONFIG.yaml --seeds 0 --actions-from FILE.json.gz --out DIR   # replay recorded actions

One env object is made per config (gym.make) and reused for all seeds, as in the published set.
The values are read from env.unwrapped; the original's methods are wrapped (never re-implemented)
to capture the diag values, the events, the group noise and the wall-clock timeouts.  The wrappers
do not touch Python's `random` or numpy's global RNG (except by calling the original functions).

Only DSRNN configs: torch/dgl and the SNGNN sub-package are replaced by stubs (stubs/sng_stubs.py),
which socnavgym imports at import time but never uses with the DSRNN reward.
"""
import argparse
import gzip
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'stubs'))
import sng_stubs  # noqa: E402
sng_stubs.install()

# This machine's environment forces OPENBLAS_CORETYPE=Haswell; the published files were made with
# the kernels OpenBLAS picks by itself on an AVX-512 CPU (Cooperlake/SkylakeX): the Haswell ddot
# (np.linalg.norm) rounds some 2-vectors differently (last-ulp differences in DISCOMFORT_DSRNN,
# MINIMUM_OBSTACLE_DISTANCE).  Let OpenBLAS detect the CPU, or take RECORDER_OPENBLAS_CORETYPE.
os.environ.pop('OPENBLAS_CORETYPE', None)
if os.environ.get('RECORDER_OPENBLAS_CORETYPE'):
    os.environ['OPENBLAS_CORETYPE'] = os.environ['RECORDER_OPENBLAS_CORETYPE']
os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')

import warnings  # noqa: E402
warnings.filterwarnings('ignore')
import numpy as np  # noqa: E402
import numpy.random  # noqa: E402
import gym  # noqa: E402
import yaml  # noqa: E402
import socnavgym  # noqa: E402,F401
from socnavgym.envs import socnavenv_v1 as M  # noqa: E402
from socnavgym.envs.utils.human import Human  # noqa: E402
from socnavgym.envs.utils.human_human import Human_Human_Interaction  # noqa: E402
from socnavgym.envs.utils.wall import Wall  # noqa: E402
from socnavgym.envs.utils.laptop import Laptop  # noqa: E402

Env = M.SocNavEnv_v1

def _blas_arch():
    try:
        import threadpoolctl
        return ",".join(str(i.get("architecture")) for i in threadpoolctl.threadpool_info()
                        if i.get("internal_api") == "openblas")
    except Exception:
        return "?"


GENERATOR = ("SocNavGym 0.1.1 (PyPI socnavgym==0.1.1), gym 0.26.2, numpy %s (OpenBLAS %s), torch/dgl "
             "stubbed (DSRNN reward only), rvo2 from pyrvo2-danieldugas 0.0.2 [socnav tools/golden-recorder/record.py]"
             % (np.__version__, _blas_arch()))
RESET_CALL = "gym.make('SocNavGym-v1', config=<yaml>) then env.reset(seed=seed)"
POLICY_KIND = "noisy_go_to_goal_mixed_with_held_random_plus_proximity_filter"
MAX_STEPS = 10000


# ----------------------------------------------------------------------------------------------
# number encoding (README section 3)

def num(v):
    """A double (or float32 held as double) -> JSON number, non-finite -> string."""
    f = float(v)
    if math.isnan(f):
        return "nan"
    if math.isinf(f):
        return "inf" if f > 0 else "-inf"
    return f


def enc(v):
    """Python/numpy value -> JSON value, keeping ints as ints and bools as bools."""
    if v is None or isinstance(v, (bool, np.bool_)):
        return None if v is None else bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return num(v)
    if isinstance(v, str):
        return v
    if isinstance(v, dict):
        return {str(k): enc(x) for k, x in v.items()}
    if isinstance(v, (list, tuple, np.ndarray)):
        return [enc(x) for x in v]
    raise TypeError("cannot encode %r (%s)" % (v, type(v)))


def f32(v):
    """float32 -> the double of its shortest round-trip decimal (written like the published obs)."""
    x = np.float32(v)
    if not np.isfinite(x):
        return num(x)
    return float(str(x))


def enc_obs(obs):
    return {k: [f32(x) for x in np.asarray(v).ravel()] for k, v in obs.items()}


# ----------------------------------------------------------------------------------------------
# recorder state and wrappers

class Rec:
    def __init__(self):
        self.env = None
        self.in_step = False
        self.sub_depth = 0
        self.in_group_goal = False
        self.noise_group = None
        self.noise_draws = []
        self.timeouts_reset = []
        self.begin_step()

    def begin_step(self):
        self.events = []
        self.replayable = True
        self.human_vel = {}
        self.group_vel = []
        self.shadow_vel = None
        self.contacts = []
        self.group_noise = []
        self.noise_seen = False
        self.sbe_candidate = None
        self.sbe = None
        self.step_timeouts = []


R = Rec()


def _wrap(cls, name, make):
    orig = getattr(cls, name)
    setattr(cls, name, make(orig))


def _check_timeout(orig):
    def f(self, start_time, period=30):
        r = orig(self, start_time, period)
        if r:
            caller = sys._getframe(1).f_code.co_name
            entry = {"function": caller, "period": period,
                     "tick": int(self.ticks) if R.in_step else None}
            (R.step_timeouts if R.in_step else R.timeouts_reset).append(entry)
        return r
    return f


def _step(orig):
    def f(self, action_pre):
        R.begin_step()
        R.in_step = True
        try:
            return orig(self, action_pre)
        finally:
            R.in_step = False
    return f


def _vel_human(kind):
    def make(orig):
        def f(self, human, *a, **k):
            policy = human.policy
            hid = human.id
            v = orig(self, human, *a, **k)
            if R.in_step:
                R.human_vel[str(hid)] = [policy, float(v[0]), float(v[1])]
            return v
        return f
    return make


def _vel_robot(orig):
    def f(self, robot):
        v = orig(self, robot)
        if R.in_step:
            R.shadow_vel = [float(v[0]), float(v[1])]
        return v
    return f


def _vel_groups(orig):
    def f(self):
        vs = orig(self)
        if R.in_step:
            R.group_vel = [[float(v[0]), float(v[1])] for v in vs]
        return vs
    return f


def _collision_force(orig):
    def f(self, a, b):
        r = orig(self, a, b)
        if R.in_step:
            R.contacts.append([a.id, b.id, b.name])
        return r
    return f


_orig_normal = numpy.random.normal


def _normal(*a, **k):
    v = _orig_normal(*a, **k)
    if R.noise_group is not None:
        R.noise_draws.append(v)
    return v


numpy.random.normal = _normal


def _group_update(orig):
    def f(self, time_, velocity=None):
        if not R.in_step or self.type != "moving":
            return orig(self, time_, velocity)
        R.noise_group = self
        R.noise_draws = []
        try:
            r = orig(self, time_, velocity)
        finally:
            R.noise_group = None
        draws = R.noise_draws
        assert len(draws) == 2 * len(self.humans), (len(draws), len(self.humans))
        if self.noise_variance != 0:
            R.noise_seen = True
            for j, h in enumerate(self.humans):
                R.group_noise.append([h.id, float(draws[2 * j]), float(draws[2 * j + 1])])
        return r
    return f


def _human_set_goal(orig):
    def f(self, gx, gy):
        orig(self, gx, gy)
        if R.in_step and R.sub_depth == 0 and not R.in_group_goal:
            R.events.append({"type": "goal_resample", "phase": "before_observation",
                             "human": self.id, "goal": [gx, gy]})
    return f


def _group_set_goal(orig):
    def f(self, gx, gy):
        R.in_group_goal = True
        try:
            orig(self, gx, gy)
        finally:
            R.in_group_goal = False
        if R.in_step and R.sub_depth == 0:
            env = R.env
            idx = [k for k, g in enumerate(env.moving_interactions) if g is self]
            assert len(idx) == 1
            R.events.append({"type": "group_goal_resample", "phase": "before_observation",
                             "group_index": idx[0], "goal": [gx, gy]})
    return f


def _index_of(lst, x):
    for k, y in enumerate(lst):
        if y is x:
            return k
    return None


def _sub(before, after, phase_after):
    """Wrap an event function: sub_depth for the goal-event filter, and the state-before-events
    snapshot (taken at the entry of the first after-observation function of the step)."""
    def make(orig):
        def f(self, *a, **k):
            if phase_after and R.in_step and R.sbe_candidate is None:
                R.sbe_candidate = snapshot(self)
            ctx = before(self, *a, **k) if before else None
            n_events = len(R.events)
            n_to = len(R.step_timeouts)
            R.sub_depth += 1
            try:
                r = orig(self, *a, **k)
            finally:
                R.sub_depth -= 1
            if after:
                after(self, ctx, n_to, *a, **k)
            if phase_after and R.in_step and len(R.events) > n_events and R.sbe is None:
                R.sbe = R.sbe_candidate
            return r
        return f
    return make


def _crowd_done_before(self, make_approx_crowd=False):
    return {"humans": [int(k) for k in self.humans_forming_crowd.keys()],
            "upcoming": getattr(self, 'upcoming_interaction', None)}


def _crowd_done_after(self, ctx, n_to, make_approx_crowd=False):
    g = self.static_interactions[-1] if make_approx_crowd else ctx["upcoming"]
    mi = _index_of(self.moving_interactions, g)
    si = _index_of(self.static_interactions, g)
    if mi is not None:
        gi, kind = mi, "moving"
    else:
        gi, kind = len(self.moving_interactions) + si, "standing"
    R.events.append({"type": "crowd_formation_complete", "phase": "before_observation",
                     "approx": bool(make_approx_crowd), "humans": ctx["humans"],
                     "group_index": gi, "group_kind": kind})
    R.replayable = False


def _hl_done_before(self):
    return {"human": self.h_l_forming_human.id, "laptop": self.upcoming_h_l_interaction.laptop.id}


def _hl_done_after(self, ctx, n_to):
    R.events.append({"type": "hl_formation_complete", "phase": "before_observation",
                     "human": ctx["human"], "laptop": ctx["laptop"]})


def _disp_before(kind):
    def before(self, index):
        lst = self.moving_interactions if kind == "moving" else self.static_interactions
        g = lst[index]
        gi = index if kind == "moving" else len(self.moving_interactions) + index
        return {"g": g, "gi": gi, "members": [h.id for h in g.humans],
                "n_static": len(self.static_humans), "n_dynamic": len(self.dynamic_humans)}
    return before


def _disp_after(kind):
    def after(self, ctx, n_to, index):
        g = ctx["g"]
        ev = {"type": "crowd_dispersal", "phase": "after_observation", "group_kind": kind,
              "group_index": ctx["gi"], "members": ctx["members"],
              "to_static": [h.id for h in self.static_humans[ctx["n_static"]:]],
              "to_dynamic": [h.id for h in self.dynamic_humans[ctx["n_dynamic"]:]]}
        if kind == "moving":
            ev["group_removed"] = _index_of(self.moving_interactions, g) is None
            ev["became_standing"] = _index_of(self.static_interactions, g) is not None
            if ev["became_standing"]:
                ev["group_removed"] = False
        else:
            ev["group_removed"] = _index_of(self.static_interactions, g) is None
        R.events.append(ev)
    return after


def _hl_disp_before(self, index):
    i = self.h_l_interactions[index]
    return {"human": i.human.id, "laptop": i.laptop.id}


def _hl_disp_after(self, ctx, n_to, index):
    R.events.append({"type": "hl_dispersal", "phase": "after_observation", "hl_index": index,
                     "human": ctx["human"], "laptop": ctx["laptop"]})


def _form_crowd_before(self):
    return {"was": bool(self.crowd_forming)}


def _form_crowd_after(self, ctx, n_to):
    if self.crowd_forming and not ctx["was"]:
        R.events.append({"type": "crowd_formation_start", "phase": "after_observation",
                         "humans": [int(k) for k in self.humans_forming_crowd.keys()]})
    elif len(R.step_timeouts) > n_to:
        R.events.append({"type": "crowd_formation_gave_up", "phase": "after_observation"})


def _form_hl_before(self):
    prev = getattr(self, 'h_l_forming_human', None)
    return {"was": bool(self.h_l_forming),
            "picks": len(self.laptops) > 0 and len(self.dynamic_humans) > 0,
            "prev_human": prev, "prev_policy": None if prev is None else prev.policy}


def _form_hl_after(self, ctx, n_to):
    if not ctx["picks"]:
        return
    if self.h_l_forming and not ctx["was"]:
        R.events.append({"type": "hl_formation_start", "phase": "after_observation",
                         "human": self.h_l_forming_human.id,
                         "laptop": self.upcoming_h_l_interaction.laptop.id})
    elif self.h_l_forming_human is not ctx["prev_human"] or \
            self.h_l_forming_human.policy != ctx["prev_policy"]:
        # The published set records a blocked draw only when it left a trace: a different human
        # drawn than at the previous laptop-formation draw, or a policy switched to ORCA
        # (exp2_no_sngnn seed 0 draws human 1 again at t=60, already ORCA: no event there).
        R.events.append({"type": "hl_formation_blocked", "phase": "after_observation",
                         "human": self.h_l_forming_human.id,
                         "policy_now": self.h_l_forming_human.policy})


def install_wrappers():
    _wrap(Env, 'check_timeout', _check_timeout)
    _wrap(Env, 'step', _step)
    _wrap(Env, 'compute_orca_velocity', _vel_human('orca'))
    _wrap(Env, 'compute_sfm_velocity', _vel_human('sfm'))
    _wrap(Env, 'compute_orca_velocity_robot', _vel_robot)
    _wrap(Env, 'compute_orca_interaction_velocities', _vel_groups)
    _wrap(Env, 'get_collision_force', _collision_force)
    _wrap(Human_Human_Interaction, 'update', _group_update)
    _wrap(Human, 'set_goal', _human_set_goal)
    _wrap(Human_Human_Interaction, 'set_goal', _group_set_goal)
    _wrap(Env, 'finish_human_crowd_formation', _sub(_crowd_done_before, _crowd_done_after, False))
    _wrap(Env, 'finish_h_l_formation', _sub(_hl_done_before, _hl_done_after, False))
    _wrap(Env, 'disperse_static_crowd', _sub(_disp_before("standing"), _disp_after("standing"), True))
    _wrap(Env, 'disperse_moving_crowd', _sub(_disp_before("moving"), _disp_after("moving"), True))
    _wrap(Env, 'disperse_human_laptop', _sub(_hl_disp_before, _hl_disp_after, True))
    _wrap(Env, 'form_human_crowd', _sub(_form_crowd_before, _form_crowd_after, True))
    _wrap(Env, 'form_human_laptop_interaction', _sub(_form_hl_before, _form_hl_after, True))


install_wrappers()


# ----------------------------------------------------------------------------------------------
# snapshot (README section 5)

def _pair(a, b):
    return None if a is None else [a, b]


def snapshot(env):
    groups_src = [("moving", g) for g in env.moving_interactions] + \
                 [("static", g) for g in env.static_interactions]
    forming_crowd = set(int(k) for k in env.humans_forming_crowd.keys()) if env.crowd_forming else set()
    forming_hl = env.h_l_forming_human if env.h_l_forming else None

    def human(h, role, extra):
        d = {"id": h.id, "x": h.x, "y": h.y, "theta": h.orientation, "speed": h.speed,
             "radius": h.width / 2, "goal": _pair(h.goal_x, h.goal_y), "goal_radius": h.goal_radius,
             "policy": h.policy, "type": h.type, "role": role, "fov": h.fov,
             "p_avoid_robot": h.prob_to_avoid_robot}
        d.update(extra)
        if h.id in forming_crowd:
            d["forming_crowd"] = True
        if forming_hl is not None and h is forming_hl:
            d["forming_hl"] = True
        return d

    humans = []
    for h in env.static_humans:
        humans.append(human(h, "static", {}))
    for h in env.dynamic_humans:
        humans.append(human(h, "dynamic", {}))
    for gi, (lst, g) in enumerate(groups_src):
        role = "moving_group" if lst == "moving" else "standing_group"
        for h in g.humans:
            humans.append(human(h, role, {"group": gi}))
    for k, i in enumerate(env.h_l_interactions):
        humans.append(human(i.human, "hl", {"hl": k}))

    groups = []
    for lst, g in groups_src:
        groups.append({"kind": "moving" if g.type == "moving" else "standing", "list": lst,
                       "dispersable": g.can_disperse, "members": [h.id for h in g.humans],
                       "centre": [g.x, g.y], "goal": _pair(g.goal_x, g.goal_y),
                       "goal_radius": g.goal_radius, "radius": g.radius, "noise": g.noise_variance})
    hls = [{"human": i.human.id, "laptop": i.laptop.id, "dispersable": i.can_disperse,
            "centre": [i.x, i.y], "distance": i.distance} for i in env.h_l_interactions]

    def laptop(l, hl):
        return {"id": l.id, "x": l.x, "y": l.y, "theta": l.orientation, "length": l.length,
                "width": l.width, "hl": hl}
    laptops = [laptop(l, None) for l in env.laptops] + \
              [laptop(i.laptop, k) for k, i in enumerate(env.h_l_interactions)]
    tables = [{"id": t.id, "x": t.x, "y": t.y, "theta": t.orientation, "length": t.length,
               "width": t.width} for t in env.tables]
    plants = [{"id": p.id, "x": p.x, "y": p.y, "radius": p.radius} for p in env.plants]

    crowd = None
    if env.crowd_forming:
        up = env.upcoming_interaction
        crowd = {"humans": [int(k) for k in env.humans_forming_crowd.keys()],
                 "slot_of": {str(k): v for k, v in env.id_to_index.items()},
                 "slots": [[h.x, h.y, h.orientation] for h in up.humans],
                 "centre": [up.x, up.y], "radius": up.radius,
                 "almost_formed_count": env.almost_formed_crowd_count}
    hlf = None
    if env.h_l_forming:
        u = env.upcoming_h_l_interaction
        hlf = {"human": env.h_l_forming_human.id, "laptop": u.laptop.id,
               "seat": [u.human.x, u.human.y, u.human.orientation]}
    r = env.robot
    ro = env.robot_orca
    rc = env.reward_calculator
    st = {
        "tick": env.ticks,
        "robot": {"x": r.x, "y": r.y, "theta": r.orientation, "radius": r.radius,
                  "goal": [r.goal_x, r.goal_y], "goal_radius": env.GOAL_RADIUS,
                  "vel": [r.vel_x, r.vel_y, r.vel_a]},
        "shadow_robot": {"x": ro.x, "y": ro.y, "theta": ro.orientation,
                         "vel": [ro.vel_x, ro.vel_y, ro.vel_a],
                         "collided": env.has_orca_robot_collided,
                         "reached": env.has_orca_robot_reached_goal,
                         "reach_tick": env.orca_robot_reach_time,
                         "path_length": env.orca_robot_path_length},
        "humans": humans,
        "groups": groups,
        "hl_interactions": hls,
        "laptops": laptops,
        "tables": tables,
        "plants": plants,
        "crowd_forming": crowd,
        "hl_forming": hlf,
        "metrics": {"prev_goal_distance": env.prev_goal_distance,
                    "failure_to_progress": env.failure_to_progress,
                    "stalled_time": env.stalled_time, "path_length": env.robot_path_length,
                    "v_min": env.v_min, "v_max": env.v_max, "v_avg": env.v_avg,
                    "prev_vel": list(env.prev_vel),
                    "a_min": env.a_min, "a_max": env.a_max, "a_avg": env.a_avg,
                    "prev_a": list(env.prev_a),
                    "jerk_min": env.jerk_min, "jerk_max": env.jerk_max, "jerk_avg": env.jerk_avg,
                    "compliant_count": env.compliant_count},
        "reward_state": {"prev_distance": getattr(rc, 'prev_distance', None), "info": dict(rc.info)},
        "goals": {str(k): (None if o is None else [o.x, o.y, o.radius]) for k, o in env.goals.items()},
    }
    if getattr(rc, 'use_sngnn', False):
        st["reward_state"]["n_frames"] = len(getattr(rc, 'sn_sequence', []))
    return enc(st)


# ----------------------------------------------------------------------------------------------
# header parts

def header_static(env):
    room = {"map_x": env.MAP_X, "map_y": env.MAP_Y, "shape": env.shape, "add_corridors": env.add_corridors}
    if env.shape == "L":
        room.update({"l_location": env.location, "l_x": env.L_X, "l_y": env.L_Y})
    F = float  # the published header writes wall/blocker geometry as floats (0.0, 10.0)
    walls = [{"id": w.id, "x": F(w.x), "y": F(w.y), "theta": F(w.orientation), "length": F(w.length),
              "thickness": F(w.thickness)} for w in env.walls]
    wall_ids = set(id(w) for w in env.walls)
    blockers = []
    for o in env.objects:
        if isinstance(o, Wall) and id(o) not in wall_ids:
            blockers.append({"kind": o.name, "x": F(o.x), "y": F(o.y), "theta": F(o.orientation),
                             "length": F(o.length), "width": F(o.thickness)})
        elif isinstance(o, Laptop) and o.id is None:
            blockers.append({"kind": o.name, "x": F(o.x), "y": F(o.y), "theta": F(o.orientation),
                             "length": F(o.length), "width": F(o.width)})
    counts = {"static_humans": env.NUMBER_OF_STATIC_HUMANS,
              "dynamic_humans": env.NUMBER_OF_DYNAMIC_HUMANS,
              "plants": env.NUMBER_OF_PLANTS, "tables": env.NUMBER_OF_TABLES,
              "laptops": env.NUMBER_OF_LAPTOPS,
              "moving_group_sizes": env.humans_in_h_h_dynamic_interactions,
              "moving_group_sizes_non_dispersing": env.humans_in_h_h_dynamic_interactions_non_dispersing,
              "standing_group_sizes": env.humans_in_h_h_static_interactions,
              "standing_group_sizes_non_dispersing": env.humans_in_h_h_static_interactions_non_dispersing,
              "hl_interactions": env.NUMBER_OF_H_L_INTERACTIONS,
              "hl_interactions_non_dispersing": env.NUMBER_OF_H_L_INTERACTIONS_NON_DISPERSING,
              "total_humans": env.total_humans}
    hp = {"orca_neighborDist": env.orca_neighborDist, "orca_timeHorizon": env.orca_timeHorizon,
          "orca_timeHorizonObst": env.orca_timeHorizonObst, "orca_maxSpeed": env.orca_maxSpeed,
          "sfm_r0": env.sfm_r0, "sfm_gamma": env.sfm_gamma, "sfm_n": env.sfm_n,
          "sfm_n_prime": env.sfm_n_prime, "sfm_lambda": env.sfm_lambd}
    return enc(room), enc(walls), enc(blockers), enc(counts), enc(hp)


def outcome_of(info, terminated, truncated):
    if info.get("OUT_OF_MAP"):
        return "out_of_map"
    if info.get("SUCCESS"):
        return "success"
    if info.get("COLLISION"):
        return "collision"
    if info.get("TIMEOUT") or truncated:
        return "timeout"
    return "cut"


# ----------------------------------------------------------------------------------------------
# scripted action policy (README section 1)

class ScriptedPolicy:
    """Own numpy Generator per episode (never touches the env's random streams).

    Per episode: p_goal ~ U(0.15, 1), p_safe ~ U(0.3, 1).  A decision is held for 1-8 steps; with
    probability p_goal it comes from a noisy go-to-goal controller (re-evaluated every step while
    held: turn toward the goal, full speed when roughly aligned), otherwise it is a uniform random
    (a0, a2) in [-1, 1]^2, sometimes exactly 0 or 1.  With probability p_safe per step a proximity
    filter stops translating toward any observed entity closer than ~0.3 m (surface distance) and
    turns away.  Actions are rounded to 4 decimals, a1 = 0.
    """

    def __init__(self, seed):
        self.rng = np.random.default_rng([seed, 0x50C1A1])
        self.p_goal = round(float(self.rng.uniform(0.15, 1.0)), 6)
        self.p_safe = round(float(self.rng.uniform(0.3, 1.0)), 6)
        self.hold = 0
        self.mode = None
        self.rand = (0.0, 0.0)
        self.noise = (0.0, 0.0)

    def params(self):
        return {"kind": POLICY_KIND, "p_goal": self.p_goal, "p_safe": self.p_safe}

    def _special(self, x):
        u = self.rng.random()
        if u < 0.1:
            return 0.0
        if u < 0.2:
            return 1.0 if x >= 0 else -1.0
        return x

    def act(self, obs):
        rng = self.rng
        robot = obs["robot"]
        gx, gy = float(robot[6]), float(robot[7])
        if self.hold > 0:
            self.hold -= 1
            a0, a2 = self.rand
        elif rng.random() < self.p_goal:
            # noisy go-to-goal controller, decided afresh every step
            ang = math.atan2(gy, gx) + float(rng.normal(0, 0.25))
            a2 = float(np.clip(1.5 * ang + rng.normal(0, 0.2), -1, 1))
            if abs(ang) < 0.4:
                a0 = float(np.clip(1.0 - abs(rng.normal(0, 0.08)) + 0.05, 0.0, 1.0))
            elif abs(ang) < 1.2:
                a0 = float(np.clip(rng.uniform(0.0, 0.6), 0.0, 1.0))
            else:
                a0 = float(rng.uniform(-0.1, 0.3))
        else:
            # uniform random decision held for 1-8 steps, sometimes exactly 0 or +-1
            self.hold = int(rng.integers(1, 9)) - 1
            self.rand = (self._special(float(rng.uniform(-1, 1))),
                         self._special(float(rng.uniform(-1, 1))))
            a0, a2 = self.rand
        if rng.random() < self.p_safe:
            rr = float(robot[8])
            worst = None
            for key in ("humans", "laptops", "tables", "plants", "walls"):
                if key not in obs:
                    continue
                v = np.asarray(obs[key], dtype=np.float64).reshape(-1, 14)
                for e in v:
                    ex, ey, er = float(e[6]), float(e[7]), float(e[10])
                    if key in ("tables", "laptops"):
                        er *= 0.6  # the observed radius circumscribes the rectangle
                    d = math.hypot(ex, ey) - er - rr
                    if d < 0.3 and ex > 0.0 and (worst is None or d < worst[0]):
                        worst = (d, ex, ey)
            if worst is not None:
                _, ex, ey = worst
                if a0 > 0:
                    a0 = 0.0
                a2 = -1.0 if ey > 0 else 1.0
        a0 = round(float(np.clip(a0, -1, 1)), 4) + 0.0
        a2 = round(float(np.clip(a2, -1, 1)), 4) + 0.0
        return [a0, 0.0, a2]


# ----------------------------------------------------------------------------------------------

def record_episode(env, cfg_name, cfg_dict, seed, actions=None, action_policy=None, policy=None):
    u = env.unwrapped
    R.env = u
    R.timeouts_reset = []
    R.begin_step()
    obs, _ = env.reset(seed=seed)
    initial = {"obs": enc_obs(obs), "state": snapshot(u)}
    room, walls, blockers, counts, hp = header_static(u)
    reset_timeouts = list(R.timeouts_reset)
    steps = []
    total = 0
    outcome = "cut"
    all_timeouts = list(reset_timeouts)
    t = 0
    while True:
        if actions is not None:
            if t >= len(actions):
                break
            a = [float(x) for x in actions[t]]
        else:
            if t >= MAX_STEPS:
                break
            a = policy.act(obs)
        obs, reward, terminated, truncated, info = env.step(np.array(a, dtype=np.float32))
        t += 1
        total += reward
        rec = {"t": u.ticks, "action": a,
               "action_processed": [u.robot.vel_x, u.robot.vel_y, u.robot.vel_a],
               "obs": enc_obs(obs), "reward": reward, "terminated": terminated,
               "truncated": truncated, "info": info, "events": R.events,
               "outputs_replayable": R.replayable,
               "diag": {"human_vel": R.human_vel, "group_orca_vel": R.group_vel,
                        "shadow_orca_vel": R.shadow_vel, "contacts": R.contacts}}
        if R.noise_seen:
            rec["group_noise"] = R.group_noise
        if R.step_timeouts:
            rec["wallclock_timeouts"] = R.step_timeouts
            all_timeouts.extend(dict(x, step=u.ticks) for x in R.step_timeouts)
        rec = {k: (v if k == "obs" else enc(v)) for k, v in rec.items()}
        if R.sbe is not None:
            rec["state_before_events"] = R.sbe
        rec["state"] = snapshot(u)
        steps.append(rec)
        if terminated or truncated:
            outcome = outcome_of(info, terminated, truncated)
            break
    header = {
        "format_version": 1,
        "generator": GENERATOR,
        "config_name": cfg_name,
        "config": cfg_dict,
        "seed": seed,
        "reset_call": RESET_CALL,
        "action_policy": action_policy if action_policy is not None else policy.params(),
        "room": room, "walls": walls, "spawn_blockers": blockers, "counts": counts,
        "human_params": hp,
        "max_steps_recorded": MAX_STEPS,
        "reward": cfg_dict["env"]["reward_file"],
        "outcome": outcome,
        "num_steps": len(steps),
        "total_reward": enc(total),
        "wallclock_timeouts": enc(all_timeouts),
        "num_event_steps": sum(1 for s in steps if s["events"]),
    }
    return {"header": header, "initial": initial, "steps": steps}


def dump(doc, path):
    text = json.dumps(doc, separators=(',', ':'), allow_nan=False)
    tmp = path + '.tmp'
    with gzip.open(tmp, 'wt', encoding='utf-8') as f:
        f.write(text)
    os.replace(tmp, path)


def parse_seeds(s):
    out = []
    for part in s.split(','):
        if '-' in part:
            a, b = part.split('-')
            out.extend(range(int(a), int(b) + 1))
        else:
            out.append(int(part))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('config')
    ap.add_argument('--seeds', required=True)
    ap.add_argument('--out', required=True)
    ap.add_argument('--name', help='config name (default: the yaml file stem)')
    ap.add_argument('--actions-from', help='published episode (or a folder of them) to take the actions from')
    ap.add_argument('--fresh-env', action='store_true', help='gym.make per episode')
    ap.add_argument('--skip-existing', action='store_true')
    args = ap.parse_args()
    name = args.name or os.path.basename(args.config).rsplit('.', 1)[0]
    with open(args.config) as f:
        cfg = yaml.safe_load(f)
    assert cfg["env"]["reward_file"] == "dsrnn", "SNGNN needs torch/dgl; this recorder stubs them"
    os.makedirs(args.out, exist_ok=True)
    env = None
    for seed in parse_seeds(args.seeds):
        path = os.path.join(args.out, "%s_seed%d.json.gz" % (name, seed))
        if args.skip_existing and os.path.exists(path):
            continue
        if env is None or args.fresh_env:
            env = gym.make("SocNavGym-v1", config=args.config)
        t0 = time.time()
        if args.actions_from:
            src = args.actions_from
            if os.path.isdir(src):
                src = os.path.join(src, "%s_seed%d.json.gz" % (name, seed))
            ref = json.load(gzip.open(src))
            actions = [s["action"] for s in ref["steps"]]
            doc = record_episode(env, name, cfg, seed, actions=actions,
                                 action_policy=ref["header"]["action_policy"])
        else:
            doc = record_episode(env, name, cfg, seed, policy=ScriptedPolicy(seed))
        dump(doc, path)
        h = doc["header"]
        print("%s seed %d: %s, %d steps, %d event steps, total reward %.4f, timeouts %d, %.1fs"
              % (name, seed, h["outcome"], h["num_steps"], h["num_event_steps"], h["total_reward"],
                 len(h["wallclock_timeouts"]), time.time() - t0), flush=True)


if __name__ == '__main__':
    main()
