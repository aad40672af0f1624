//! Field-by-field comparison of socnav's outputs and state with a golden step.
//!
//! Tolerances (each justified where it is used) come from one fact: the reference computes in
//! f64 except where it holds float32 (RVO2, observations, the processed action, V/A/JERK), while
//! socnav computes in f32 from the f32-rounded recorded state. One step of f32 arithmetic on
//! metre-scale values differs from f64 by a few 1e-7; the observation went through float32 3x3
//! matrix inverses in the reference, a few ulp of values up to ~15 m.

use std::f64::consts::PI;

use serde_json::Value;
use socnav::BatchEnv;
use socnav::config::{ContactShape, ObsFrame, RewardKind};
use socnav::spec::{ENTITY_KEYS, INFO_KEYS, RECORD, info};

use super::conditioning::{Kinematics, Widen, extent, goal_distance_change_error, widening};
use super::contact::{ContactRule, Near, near_contact, shadow_collided};
use super::corrected::{
    Outcome, Perturbation, dsrnn_discomfort, time_to_collision, time_to_collision_outcomes,
    time_to_collision_possible, wrapped_angular_speed,
};
use super::{Episode, Step, num};

/// Absolute tolerance on positions and distances (m): a few f32 ulp at 16 m is 1e-5.
pub(super) const POS: f64 = 2e-5;
/// Absolute tolerance on velocities (m/s) and accumulated metrics.
const VEL: f64 = 2e-6;
/// Absolute tolerance on observation entries: the reference's float32 matrix inverses round
/// positions of up to ~15 m by a few ulp (1e-6 each).
const OBS: f64 = 3e-5;
/// Absolute tolerance on rewards: the distance term is 5·(d_t − d_{t−1}) for goal distances of up
/// to ~15 m, whose f32 rounding (≤ 1e-6 each) the factor 5 and the cancellation amplify to ~1e-5.
const REWARD: f64 = 1.2e-5;
/// Absolute tolerance on SNGNN-v2's terms (issue 6): the network's output within 1e-4 of the
/// original's, which ran it in float32 with PyTorch's summation order.
const SNGNN: f64 = 1e-4;
/// Max-error bucket of the values that needed their tolerance widened for ill-conditioning.
const CONDITIONED: usize = 4;
/// Max-error bucket of headings (rad) and the observation's heading terms of humans (sin, cos,
/// angular speed) within the common tolerance.
const HEADING: usize = 5;
/// Max-error bucket of TIME_TO_COLLISION values (steps) that only ill-conditioned decisions
/// explain.
const TTC: usize = 6;
/// Failures listed in full before the rest are only counted (`SOCNAV_GOLDEN_SHOW` overrides).
fn shown() -> usize {
    std::env::var("SOCNAV_GOLDEN_SHOW")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40)
}

/// What one or more replays found.
#[derive(Default)]
pub struct Report {
    name: String,
    compared: u64,
    failures: Vec<String>,
    failure_count: u64,
    /// Decisions within their conditioning that socnav took the other way (counted against the
    /// budget of [`Report::assert_ok`]).
    flips: u64,
    /// Contacts that exact discs decided differently from 0.1.1's 64-gons within the polygon's
    /// inset: explained by the shape (the replay with `contact_shape = "polygon64"` decides them
    /// as 0.1.1 does), so outside the budget.
    shape_flips: u64,
    /// Flips that start a situation: a flip of a kind and a body that did not flip at the
    /// previous step. A walker that ORCA holds at an object's surface for N steps flips every
    /// step for one reason, one coincidence and not N; the budget applies to these.
    flip_streaks: u64,
    /// Shape flips that start a situation (as `flip_streaks`).
    shape_flip_streaks: u64,
    /// The situations that flipped at the previous step and at this one (`kind body` keys).
    previous_flips: Vec<String>,
    current_flips: Vec<String>,
    /// How socnav decides contacts in this replay (exact discs unless set).
    rule: Option<ContactRule>,
    /// Values that differ by more than their common tolerance but within their derived
    /// conditioning (tests/golden/conditioning.rs), and time-to-collision values that only an
    /// ill-conditioned decision explains.
    ill_conditioned: u64,
    steps: u64,
    /// Largest error seen per kind: positions, velocities, observations, rewards, values that
    /// needed their tolerance widened for ill-conditioning (slow headings and walkers near
    /// their goal), headings, and time-to-collision steps of ill-conditioned decisions.
    max_err: [(f64, String); 7],
}

impl Report {
    pub fn new(name: &str) -> Self {
        Self {
            name: name.to_string(),
            ..Default::default()
        }
    }

    /// A report of a replay whose batch decides contacts with `shape` (for humans of
    /// `human_radius`, m).
    pub fn with_contact_shape(mut self, shape: ContactShape, human_radius: f64) -> Self {
        self.rule = Some(ContactRule::new(shape, human_radius));
        self
    }

    /// The contact rule of this replay (exact discs by default).
    fn rule(&self, env: &BatchEnv) -> ContactRule {
        self.rule.unwrap_or_else(|| {
            ContactRule::new(
                env.config().model.contact_shape,
                env.params().human_radius as f64,
            )
        })
    }

    /// Count a contact decided differently within its bracket: a shape flip with exact discs,
    /// a flip otherwise. `key` names the situation (see [`Self::flip`]).
    fn contact_flip(&mut self, rule: &ContactRule, key: String) {
        self.flip(key, rule.shape == ContactShape::Exact);
    }

    /// Count a near-threshold flip (`shape`: a shape flip, outside the budget) of the situation
    /// `key` (the decision's kind and the body it concerns): it starts a streak unless the same
    /// situation flipped at the previous step in the same category (a flip inside the budget
    /// that continues only a shape-flip streak starts a streak of its own).
    fn flip(&mut self, key: String, shape: bool) {
        let key = format!("{}{key}", if shape { "shape " } else { "" });
        let new = !self.previous_flips.contains(&key);
        if shape {
            self.shape_flips += 1;
            self.shape_flip_streaks += u64::from(new);
        } else {
            self.flips += 1;
            self.flip_streaks += u64::from(new);
        }
        self.current_flips.push(key);
    }

    pub fn summary(&self) -> String {
        format!(
            "{} steps, {} values compared, {} mismatches, {} near-threshold flips ({} streaks), {} contacts within the 64-gon's inset ({} streaks), {} ill-conditioned values; max |err| pos {:.2e} ({}), heading {:.2e} ({}), vel {:.2e} ({}), obs {:.2e} ({}), reward {:.2e} ({}), ill-conditioned {:.2e} ({}), time to collision {:.3e} steps ({})",
            self.steps,
            self.compared,
            self.failure_count,
            self.flips,
            self.flip_streaks,
            self.shape_flips,
            self.shape_flip_streaks,
            self.ill_conditioned,
            self.max_err[0].0,
            self.max_err[0].1,
            self.max_err[HEADING].0,
            self.max_err[HEADING].1,
            self.max_err[1].0,
            self.max_err[1].1,
            self.max_err[2].0,
            self.max_err[2].1,
            self.max_err[3].0,
            self.max_err[3].1,
            self.max_err[4].0,
            self.max_err[4].1,
            self.max_err[TTC].0,
            self.max_err[TTC].1
        )
    }

    pub fn merge(&mut self, other: &Report) {
        self.compared += other.compared;
        self.failure_count += other.failure_count;
        self.flips += other.flips;
        self.shape_flips += other.shape_flips;
        self.flip_streaks += other.flip_streaks;
        self.shape_flip_streaks += other.shape_flip_streaks;
        self.ill_conditioned += other.ill_conditioned;
        self.steps += other.steps;
        for (a, b) in self.max_err.iter_mut().zip(&other.max_err) {
            if b.0 > a.0 {
                *a = (b.0, format!("{}: {}", other.name, b.1));
            }
        }
        for f in &other.failures {
            if self.failures.len() < shown() {
                self.failures.push(format!("{}: {f}", other.name));
            }
        }
    }

    /// No mismatch, and at most one near-threshold flip streak per 500 steps: flips are rare
    /// threshold coincidences of f32 against 0.1.1's f64, more mean a real difference. A flip
    /// that continues the same situation's flip at the previous step (a walker held at an
    /// object's surface by ORCA) is part of one coincidence, so the budget counts streaks.
    /// Contacts within the 64-gon's inset under exact discs are outside the budget (the
    /// polygon64 replay decides them).
    pub fn assert_ok(&self) {
        assert!(self.compared > 0, "nothing was compared");
        assert!(
            self.failure_count == 0,
            "{} mismatches ({} near-threshold flips in {} steps):\n{}",
            self.failure_count,
            self.flips,
            self.steps,
            self.failures.join("\n")
        );
        assert!(
            self.flip_streaks * 500 <= self.steps.max(500),
            "{} near-threshold flip streaks ({} flips) in {} steps",
            self.flip_streaks,
            self.flips,
            self.steps
        );
    }

    /// Mismatches found (all of them, also those not listed).
    pub fn failure_count(&self) -> u64 {
        self.failure_count
    }

    /// The mismatches listed (the first `SOCNAV_GOLDEN_SHOW`, default 40).
    pub fn failures(&self) -> &[String] {
        &self.failures
    }

    /// Decisions counted as near-threshold flips.
    pub fn flips(&self) -> u64 {
        self.flips
    }

    /// Contacts exact discs decided differently within the 64-gon's inset.
    pub fn shape_flips(&self) -> u64 {
        self.shape_flips
    }

    /// Near-threshold flips that start a streak (what the budget counts).
    pub fn flip_streaks(&self) -> u64 {
        self.flip_streaks
    }

    /// Values accepted only within their derived conditioning.
    pub fn ill_conditioned(&self) -> u64 {
        self.ill_conditioned
    }

    fn fail(&mut self, msg: String) {
        self.failure_count += 1;
        if self.failures.len() < shown() {
            self.failures.push(msg);
        }
    }

    /// Compare `ours` with `theirs` within `abs` (+ `rel`·|theirs|); `kind` picks the max-error bucket.
    fn close(&mut self, what: &str, ours: f64, theirs: f64, abs: f64, kind: usize) {
        self.compared += 1;
        let same = (ours.is_nan() && theirs.is_nan()) || ours == theirs;
        let err = (ours - theirs).abs();
        // A NaN error (one side NaN) must fail, hence the explicit comparison.
        let within = err.partial_cmp(&abs).is_some_and(|o| o.is_le());
        if !same && !within {
            self.fail(format!(
                "{what}: ours {ours} vs reference {theirs} (|err| {err:.3e} > {abs:.1e})"
            ));
        } else if err.is_finite() && err > self.max_err[kind].0 {
            self.max_err[kind] = (err, what.to_string());
        }
    }

    /// [`Self::close`] within `abs`, or within `abs` + `extra`, `extra` being a derived
    /// widening for ill-conditioning: a value that needs it is counted and goes to the
    /// ill-conditioned max-error bucket.
    fn widened(
        &mut self,
        what: &str,
        ours: f64,
        theirs: f64,
        (abs, extra): (f64, f64),
        kind: usize,
    ) {
        let err = (ours - theirs).abs();
        if extra == 0.0 || err.is_nan() || err <= abs {
            self.close(what, ours, theirs, abs, kind);
            return;
        }
        let failures = self.failure_count;
        self.close(what, ours, theirs, abs + extra, CONDITIONED);
        if self.failure_count == failures {
            self.ill_conditioned += 1;
        }
    }

    /// Headings (rad), compared modulo 2π; `extra` widens the tolerance for ill-conditioning.
    fn angle(&mut self, what: &str, ours: f64, theirs: f64, extra: f64) {
        let d = (ours - theirs).sin().atan2((ours - theirs).cos());
        self.widened(what, theirs + d, theirs, (POS, extra), HEADING);
    }

    fn equal(&mut self, what: &str, ours: &Value, theirs: &Value) {
        self.compared += 1;
        if ours != theirs {
            self.fail(format!("{what}: ours {ours} vs reference {theirs}"));
        }
    }

    /// The observation of environment 0 against a golden observation dict.
    /// `humans` widens the tolerance of each human's velocity-derived terms
    /// (`conditioning::widening`); humans marked in `flipped` are not compared.
    pub fn compare_obs(
        &mut self,
        env: &BatchEnv,
        golden: &Value,
        humans: &[Widen],
        flipped: &[bool],
        at: &str,
    ) {
        let out = env.outputs();
        let layout = env.layout();
        let robot = golden["robot"].as_array().expect("robot record");
        for (k, v) in robot.iter().enumerate() {
            self.close(
                &format!("{at} obs.robot[{k}]"),
                out.obs[k] as f64,
                num(v),
                OBS,
                2,
            );
        }
        for (t, key) in ENTITY_KEYS.iter().enumerate() {
            let theirs = golden
                .get(*key)
                .and_then(Value::as_array)
                .map_or(&[][..], |v| &v[..]);
            let count = out.obs_count[t] as usize;
            self.compared += 1;
            if count * RECORD != theirs.len() {
                self.fail(format!(
                    "{at} obs.{key}: {count} records vs {} in the reference",
                    theirs.len() / RECORD
                ));
                continue;
            }
            let ours = &out.obs[layout.offset[t]..layout.offset[t] + count * RECORD];
            for (i, (o, g)) in ours.iter().zip(theirs).enumerate() {
                if t == 0 && flipped.get(i / RECORD).copied().unwrap_or(false) {
                    continue;
                }
                let mut g = num(g);
                if t == 0 && i % RECORD == 13 && *o as f64 != g {
                    let record = &theirs[i - 13..i + 1];
                    let w = humans.get(i / RECORD).copied().unwrap_or_default();
                    if self.gaze_ill_conditioned(env, robot, record, w) {
                        self.compared += 1;
                        self.ill_conditioned += 1;
                        continue;
                    }
                }
                if t == 0 && i % RECORD == 12 {
                    // Relative angular speed: socnav wraps the heading difference (0.1.1 does not).
                    // A difference of ±π sits on the seam of the wrap, where rounding picks either
                    // end; both name the same rotation, so the two are compared modulo 2π.
                    let dt = env.params().dt as f64;
                    g = wrapped_angular_speed(g, dt);
                    g = *o as f64 + wrapped_angular_speed(g - *o as f64, dt);
                }
                // Velocity-derived terms: position (moved by speed·dt), heading sin and cos
                // (rad-sized errors), relative speed and angular speed (rad/s).
                let w = humans.get(i / RECORD).copied().unwrap_or_default();
                let dt = env.params().dt as f64;
                let extra = match (t, i % RECORD) {
                    (0, 6 | 7) => w.velocity * dt,
                    (0, 8 | 9) => w.heading,
                    (0, 11) => w.velocity,
                    (0, 12) => w.heading / dt,
                    _ => 0.0,
                };
                let kind = match (t, i % RECORD) {
                    (0, 8 | 9 | 12) => HEADING,
                    _ => 2,
                };
                self.widened(
                    &format!("{at} obs.{key}[{}][{}]", i / RECORD, i % RECORD),
                    *o as f64,
                    g,
                    (OBS, extra),
                    kind,
                );
            }
        }
    }

    /// F3: whether a human's gaze bit (robot centre within ±gaze_angle/2 of its heading) is
    /// decided within the conditioning of its record (`record`, the recorded 14 values; `robot`,
    /// the recorded robot record; `w`, the human's widening).
    ///
    /// The bearing β = angle(robot − human) − heading is compared with gaze_angle/2. socnav's
    /// heading may differ from 0.1.1's by the heading tolerance POS + `w.heading` (π for a
    /// walker whose velocity is exactly 0 in RVO2 and ~1e-7 m/s in socnav's ORCA: any heading);
    /// the direction to the robot moves by at most the positions' tolerances over the distance
    /// d, (POS (robot) + POS + `w.velocity`·dt (human))/d; the recorded record is float32 (OBS
    /// on its positions, so OBS/d twice, and on its sin and cos, OBS); socnav holds
    /// gaze_angle/2 in f32 (≤ ulp(π) off). Within that sum of the boundary, either bit is
    /// accepted and counted as ill-conditioned. No other discrete entry of a human record
    /// depends on a heading (the one-hot and the visibility, which depends on the robot's
    /// heading, which is compared within POS).
    fn gaze_ill_conditioned(
        &self,
        env: &BatchEnv,
        robot: &[Value],
        record: &[Value],
        w: Widen,
    ) -> bool {
        let (x, y, s, c) = (
            num(&record[6]),
            num(&record[7]),
            num(&record[8]),
            num(&record[9]),
        );
        let (dx, dy) = match env.config().observation.frame {
            ObsFrame::Robot => (-x, -y),
            ObsFrame::World => (num(&robot[8]) - x, num(&robot[9]) - y),
        };
        let bearing = (c * dy - s * dx).atan2(c * dx + s * dy);
        let half = 0.5 * f64::from(env.params().gaze_angle);
        let distance = dx.hypot(dy);
        let dt = env.params().dt as f64;
        let tolerance = POS
            + w.heading
            + OBS
            + (2.0 * POS + w.velocity * dt + 2.0 * OBS) / distance
            + super::conditioning::ulp(PI);
        (bearing.abs() - half).abs() <= tolerance
    }

    /// Outputs and state of one step.
    pub fn compare_step(&mut self, env: &BatchEnv, ep: &Episode, step: Step<'_>, prev: &Value) {
        self.steps += 1;
        self.previous_flips = std::mem::take(&mut self.current_flips);
        let at = format!("t={}", step.t());
        let out = env.outputs();
        let post = step.state_after_motion();
        let (term, trunc) = (out.terminated[0] != 0, out.truncated[0] != 0);
        let g_term = step.v["terminated"].as_bool().expect("terminated");
        let g_trunc = step.v["truncated"].as_bool().expect("truncated");
        if (term, trunc) != (g_term, g_trunc) {
            let rule = self.rule(env);
            if self.near_threshold(env, ep.header(), post, &rule) {
                self.contact_flip(&rule, "termination robot".to_string());
                println!(
                    "  flip at {at}: terminated ours {term} vs reference {g_term} (a robot contact within {:.1e} of the radii, {:?} shape)",
                    rule.fraction, rule.shape
                );
                return;
            }
            self.fail(format!("{at}: terminated/truncated ours ({term}, {trunc}) vs reference ({g_term}, {g_trunc})"));
            return;
        }
        // A crowd that formed during the step was laid out at random (golden README section 8):
        // nothing after it can be compared.
        if !step.replayable() {
            return;
        }
        let ours = env.get_state(0).expect("get_state");
        let flipped = self.contact_flips(env, ep, &step, &ours["state"], &at);
        let p = env.params();
        let kinematics = Kinematics {
            dt: p.dt as f64,
            human_radius: p.human_radius as f64,
            human_max_speed: p.human_max_speed as f64,
            robot_max_speed: p.robot_max_speed as f64,
        };
        let (shadow_widen, humans) = widening(ep.header(), prev, &step, &kinematics);
        self.compare_obs(env, &step.v["obs"], &humans, &flipped, &at);
        let ftp = self.failure_to_progress(prev, post, &ours["state"], &at);
        let knock_on = flipped
            .iter()
            .any(|&f| f)
            .then(|| with_flipped_from(post, &ours["state"], &flipped));
        let robot_radius = p.robot_radius as f64;
        let compliant = |s: &Value| {
            f64::from(u8::from(
                minimum_distance_to_human(s) - robot_radius >= PERSONAL_SPACE,
            ))
        };
        let ctx = Context {
            header: ep.header(),
            ours: &ours["state"],
            ftp,
            dt: kinematics.dt,
            at: &at,
            knock_on: knock_on.as_ref(),
            compliant_change: knock_on
                .as_ref()
                .map_or(0.0, |k| compliant(k) - compliant(post)),
            tick: step.t() as f64,
        };
        self.compare_info(env, step.v, post, &ctx);
        let shadow = self.shadow_collided(env, ep, (prev, post, &ours["state"]), &at);
        let widen = StateWidening {
            shadow: shadow_widen,
            humans: &humans,
            flipped: &flipped,
            shadow_collided: shadow,
        };
        self.compare_state(&ours["state"], post, &step, &widen, &ctx);
    }

    /// The FAILURE_TO_PROGRESS count socnav must report. 0.1.1 counts d_t > d_{t−1} in f64,
    /// socnav in f32: where the recorded change is within the bound on socnav's f32 change
    /// (`conditioning::goal_distance_change_error`) the decision is ill-conditioned, and socnav
    /// may count the other way (one more where 0.1.1 did not count, one less where it did): a
    /// near-threshold flip. A robot that did not move has exactly equal distances on both sides
    /// (socnav recomputes the previous one from the same f32 pose).
    fn failure_to_progress(&mut self, prev: &Value, post: &Value, ours: &Value, at: &str) -> f64 {
        let recorded = num(&post["metrics"]["failure_to_progress"]);
        let counted = recorded - num(&prev["metrics"]["failure_to_progress"]);
        let theirs = num(&ours["metrics"]["failure_to_progress"]);
        let pose = |s: &Value| (num(&s["robot"]["x"]), num(&s["robot"]["y"]));
        let (before, after) = (pose(prev), pose(post));
        let goal = &post["robot"]["goal"];
        let goal = (num(&goal[0]), num(&goal[1]));
        let distance = |(x, y): (f64, f64)| (goal.0 - x).hypot(goal.1 - y);
        let change = distance(after) - distance(before);
        let bound = goal_distance_change_error(before, after, goal);
        let other = recorded + 1.0 - 2.0 * counted;
        if before != after && change.abs() <= bound && theirs == other {
            self.flip("failure_to_progress robot".to_string(), false);
            println!(
                "  flip at {at}: FAILURE_TO_PROGRESS {theirs} vs reference {recorded} (goal distance change {change:.2e} m within f32 rounding {bound:.2e} m)"
            );
            return other;
        }
        recorded
    }

    /// The shadow robot's `collided` flag socnav must report: 0.1.1 tests groups and laptop
    /// users against the real robot (docs/fidelity.md). Checks that reconstruction, with 0.1.1's
    /// 64-gons, against the recording, then returns the corrected flag decided with socnav's
    /// shape. A decision that only contact distances within its rule's bracket change is a flip.
    fn shadow_collided(
        &mut self,
        env: &BatchEnv,
        ep: &Episode,
        (prev, post, ours): (&Value, &Value, &Value),
        at: &str,
    ) -> bool {
        let p = env.params();
        let radii = (p.robot_radius as f64, p.human_radius as f64);
        let decide = |bug: bool, rule: &ContactRule, target: bool| {
            let flag = |scale| shadow_collided(ep.header(), (prev, post), radii, bug, rule, scale);
            let decided = flag(1.0);
            (decided, decided != target && rule.ambiguous(flag))
        };
        let recorded = post["shadow_robot"]["collided"] == true;
        let theirs = ContactRule::new(ContactShape::Polygon64, radii.1);
        let (buggy, flip) = decide(true, &theirs, recorded);
        if flip {
            self.flip("0.1.1_shadow_collided shadow_robot".to_string(), false);
            println!(
                "  flip at {at}: 0.1.1's shadow-robot contact is within f32 rounding of its 64-gons"
            );
        } else {
            self.equal(
                &format!("{at} reconstruction of 0.1.1's shadow_robot.collided"),
                &Value::Bool(buggy),
                &Value::Bool(recorded),
            );
        }
        let ours = ours["shadow_robot"]["collided"] == true;
        let rule = self.rule(env);
        let (fixed, flip) = decide(false, &rule, ours);
        if flip {
            self.contact_flip(&rule, "shadow_collided shadow_robot".to_string());
            println!(
                "  flip at {at}: socnav's shadow-robot contact is within {:.1e} of the radii ({:?} shape)",
                rule.fraction, rule.shape
            );
            return ours;
        }
        fixed
    }

    /// Humans whose contact push-out was decided differently within the 64-gon margin
    /// (`contact::near_contact`) and who therefore ended the step elsewhere: counted as flips,
    /// left out of the comparison.
    fn contact_flips(
        &mut self,
        env: &BatchEnv,
        ep: &Episode,
        step: &Step<'_>,
        ours: &Value,
        at: &str,
    ) -> Vec<bool> {
        let p = env.params();
        let rule = self.rule(env);
        let (dt, radius, max_speed) =
            (p.dt as f64, p.human_radius as f64, p.human_max_speed as f64);
        let near = near_contact(ep.header(), step, (dt, radius, max_speed), &rule);
        let theirs = step.state_after_motion()["humans"]
            .as_array()
            .cloned()
            .unwrap_or_default();
        let ours = ours["humans"].as_array().cloned().unwrap_or_default();
        near.iter()
            .zip(theirs.iter().zip(&ours))
            .map(|(&near, (t, o))| {
                let moved = (num(&o["x"]) - num(&t["x"])).hypot(num(&o["y"]) - num(&t["y"])) > POS;
                let flip = near != Near::No && moved && o["id"] == t["id"];
                if flip {
                    let key = format!("contact human {}", t["id"]);
                    if near == Near::Repeated {
                        self.flip(key, false);
                    } else {
                        self.contact_flip(&rule, key);
                    }
                    println!(
                        "  flip at {at}: human {} touches an object within {:.1e} of its radius ({:?} shape{}) and was pushed by one side only",
                        t["id"],
                        rule.fraction,
                        rule.shape,
                        if near == Near::Repeated { ", bracket widened for its earlier pushes" } else { "" }
                    );
                }
                flip
            })
            .collect()
    }

    /// Is the robot's collision with a human or an object decided within the rule's bracket?
    fn near_threshold(
        &self,
        env: &BatchEnv,
        header: &Value,
        post: &Value,
        rule: &ContactRule,
    ) -> bool {
        let p = env.params();
        let robot = &post["robot"];
        let robot = (num(&robot["x"]), num(&robot["y"]), p.robot_radius as f64);
        let human_radius = p.human_radius as f64;
        let humans = post["humans"].as_array().cloned().unwrap_or_default();
        let used_laptops: Vec<Value> = post["laptops"]
            .as_array()
            .into_iter()
            .flatten()
            .filter(|l| !l["hl"].is_null())
            .cloned()
            .collect();
        rule.ambiguous(|scale| {
            humans
                .iter()
                .any(|h| rule.discs_touch(robot, (num(&h["x"]), num(&h["y"]), human_radius), scale))
                || used_laptops
                    .iter()
                    .any(|l| rule.touches_rect(robot, l, "width", scale))
                || rule.touches_object(header, post, robot, scale)
        })
    }

    fn compare_info(&mut self, env: &BatchEnv, step: &Value, post: &Value, ctx: &Context<'_>) {
        let at = ctx.at;
        let out = env.outputs();
        let p = env.params();
        let golden = &step["info"];
        let terminal =
            step["terminated"].as_bool() == Some(true) || step["truncated"].as_bool() == Some(true);
        let dt = p.dt as f64;
        let (rr, hr) = (p.robot_radius as f64, p.human_radius as f64);
        // The recorded discomfort must be what 0.1.1's formula gives (checks this reconstruction);
        // socnav's must be the corrected one. Terminal steps repeat the previous value (persisted).
        let mut discomfort = num(&golden["DISCOMFORT_DSRNN"]);
        let mut reward = num(&step["reward"]);
        // With SNGNN-v2's reward the DSRNN discomfort is in the info only, not in the reward.
        let sngnn = env.config().reward.kind == RewardKind::Sngnn;
        let no_groups = post["groups"].as_array().is_none_or(Vec::is_empty)
            && post["hl_interactions"].as_array().is_none_or(Vec::is_empty);
        if !terminal {
            if no_groups {
                let buggy = dsrnn_discomfort(post, dt, rr, hr, true);
                // 2e-8: the reference holds the human radius as float32 (0.36000001), which shifts d_min by 1.4e-8.
                self.close(
                    &format!("{at} reconstruction of 0.1.1's DISCOMFORT_DSRNN"),
                    buggy,
                    discomfort,
                    2e-8,
                    3,
                );
            }
            // F2: with a contact flip, the discomfort (and the reward through it) of socnav's
            // positions of the flipped humans (`with_flipped_from`).
            let fixed = dsrnn_discomfort(ctx.knock_on.unwrap_or(post), dt, rr, hr, false);
            if !sngnn {
                reward += fixed - discomfort;
            }
            discomfort = fixed;
        } else {
            discomfort = num(
                &env.get_state(0).unwrap()["state"]["reward_state"]["info"]["DISCOMFORT_DSRNN"],
            );
        }
        self.close(
            &format!("{at} reward"),
            out.reward[0] as f64,
            reward,
            if sngnn { REWARD + SNGNN } else { REWARD },
            3,
        );
        // TIME_TO_COLLISION: the recording against 0.1.1's formula evaluated with every
        // decision that f32 rounding can flip (0.1.1 computes it in float32), socnav's value
        // (laptop users counted) against the corrected formula with every decision that
        // rounding and socnav's state differences can flip.
        let ttc = time_to_collision(post, dt, rr, hr, false);
        let x = extent(ctx.header, &[post, ctx.ours], hr);
        let rounding = |_| Perturbation::default();
        let buggy = time_to_collision_outcomes(post, dt, (rr, hr), true, x, &rounding);
        self.time_to_collision(
            &format!("{at} reconstruction of 0.1.1's TIME_TO_COLLISION"),
            num(&golden["TIME_TO_COLLISION"]),
            time_to_collision(post, dt, rr, hr, true),
            &buggy,
        );
        let differences = |k| state_differences(ctx.ours, post, k);
        let fixed = time_to_collision_outcomes(post, dt, (rr, hr), false, x, &differences);
        self.time_to_collision(
            &format!("{at} info.TIME_TO_COLLISION"),
            out.info[info::TIME_TO_COLLISION] as f64,
            ttc,
            &fixed,
        );
        // MINIMUM_DISTANCE_TO_HUMAN: 0.1.1's formula reproduces the recording (checked where it is
        // used) (f64, the same
        // operations: 1e-12 covers libm's last-ulp sqrt differences); with a contact flip,
        // socnav's value is the formula on socnav's positions of the flipped humans (F2), and
        // the personal-space compliance decision that follows from it may change by one count.
        let recorded_distance = num(&golden["MINIMUM_DISTANCE_TO_HUMAN"]);
        if ctx.knock_on.is_some() {
            self.close(
                &format!("{at} reconstruction of 0.1.1's MINIMUM_DISTANCE_TO_HUMAN"),
                minimum_distance_to_human(post),
                recorded_distance,
                1e-12,
                0,
            );
        }
        for (k, key) in INFO_KEYS.iter().enumerate() {
            if k == info::TIME_TO_COLLISION {
                continue;
            }
            let ours = out.info[k] as f64;
            let theirs = match k {
                info::DISCOMFORT_DSRNN => discomfort,
                info::FAILURE_TO_PROGRESS => ctx.ftp,
                info::MINIMUM_DISTANCE_TO_HUMAN => ctx
                    .knock_on
                    .map_or(recorded_distance, minimum_distance_to_human),
                info::PERSONAL_SPACE_COMPLIANCE => {
                    num(&golden[*key]) + ctx.compliant_change / ctx.tick
                }
                _ => num(&golden[*key]),
            };
            let tol = match k {
                info::MINIMUM_DISTANCE_TO_HUMAN
                | info::MINIMUM_OBSTACLE_DISTANCE
                | info::AVERAGE_OBSTACLE_DISTANCE => POS,
                info::PATH_LENGTH | info::STALLED_TIME => 1e-5,
                info::DISTANCE_REWARD => REWARD,
                info::DISCOMFORT_DSRNN => 2e-6,
                info::DISCOMFORT_SNGNN | info::SNGNN_REWARD => SNGNN,
                _ => VEL,
            };
            self.close(&format!("{at} info.{key}"), ours, theirs, tol, 1);
        }
    }

    /// A TIME_TO_COLLISION `value` against the set of values its decisions allow
    /// (`corrected::time_to_collision_outcomes`); `nominal` is the formula's value on the
    /// snapshot. A value other than the nominal one is ill-conditioned.
    fn time_to_collision(
        &mut self,
        what: &str,
        value: f64,
        nominal: f64,
        outcomes: &[Vec<Outcome>],
    ) {
        self.compared += 1;
        if !time_to_collision_possible(outcomes, nominal) {
            self.fail(format!(
                "{what}: the nominal value {nominal} is outside its own conditioning {outcomes:?}"
            ));
        } else if !time_to_collision_possible(outcomes, value) {
            self.fail(format!(
                "{what}: {value} vs {nominal}, not a value its decisions allow {outcomes:?}"
            ));
        } else if value != nominal {
            self.ill_conditioned += 1;
            // A predicted collision against none (−1) has no size; it is only counted.
            let err = (value - nominal).abs();
            if value >= 0.0 && nominal >= 0.0 && err > self.max_err[TTC].0 {
                self.max_err[TTC] = (err, what.to_string());
            }
        }
    }

    fn compare_state(
        &mut self,
        ours: &Value,
        theirs: &Value,
        step: &Step<'_>,
        widen: &StateWidening<'_>,
        ctx: &Context<'_>,
    ) {
        let at = ctx.at;
        let (resampled_humans, resampled_groups) = step.resampled();
        // The shadow robot drives at its RVO2 velocity (diff-drive: at its speed, vel[0];
        // holonomic: its robot-frame components, vel[0] and vel[1]) and turns towards it, by the
        // unwrapped heading error per step: the command and the position carry the velocity's
        // conditioning, the heading and the turn rate (vel[2], the heading change over dt) the
        // direction's (`conditioning::widening`).
        for (key, w) in [("robot", Widen::default()), ("shadow_robot", widen.shadow)] {
            let (o, t) = (&ours[key], &theirs[key]);
            let moved = (POS, w.velocity * ctx.dt);
            self.widened(
                &format!("{at} {key}.x"),
                num(&o["x"]),
                num(&t["x"]),
                moved,
                0,
            );
            self.widened(
                &format!("{at} {key}.y"),
                num(&o["y"]),
                num(&t["y"]),
                moved,
                0,
            );
            self.angle(
                &format!("{at} {key}.theta"),
                num(&o["theta"]),
                num(&t["theta"]),
                w.heading,
            );
            for (k, extra) in [w.velocity, w.velocity, w.heading / ctx.dt]
                .into_iter()
                .enumerate()
            {
                self.widened(
                    &format!("{at} {key}.vel[{k}]"),
                    num(&o["vel"][k]),
                    num(&t["vel"][k]),
                    (VEL, extra),
                    1,
                );
            }
        }
        let (os, ts) = (&ours["shadow_robot"], &theirs["shadow_robot"]);
        self.equal(
            &format!("{at} shadow_robot.collided"),
            &os["collided"],
            &Value::Bool(widen.shadow_collided),
        );
        for key in ["reached", "reach_tick"] {
            self.equal(&format!("{at} shadow_robot.{key}"), &os[key], &ts[key]);
        }
        self.close(
            &format!("{at} shadow_robot.path_length"),
            num(&os["path_length"]),
            num(&ts["path_length"]),
            1e-5,
            0,
        );
        let oh = ours["humans"].as_array().expect("humans");
        let th = theirs["humans"].as_array().expect("humans");
        self.compared += 1;
        if oh.len() != th.len() {
            self.fail(format!("{at}: {} humans vs {}", oh.len(), th.len()));
            return;
        }
        for (k, (o, t)) in oh.iter().zip(th).enumerate() {
            if widen.flipped.get(k).copied().unwrap_or(false) {
                continue;
            }
            let who = format!("{at} humans[{k}] (id {})", t["id"]);
            let w = widen.humans.get(k).copied().unwrap_or_default();
            self.equal(&format!("{who}.id"), &o["id"], &t["id"]);
            self.equal(&format!("{who}.role"), &o["role"], &t["role"]);
            let moved = (POS, w.velocity * ctx.dt);
            self.widened(&format!("{who}.x"), num(&o["x"]), num(&t["x"]), moved, 0);
            self.widened(&format!("{who}.y"), num(&o["y"]), num(&t["y"]), moved, 0);
            self.widened(
                &format!("{who}.speed"),
                num(&o["speed"]),
                num(&t["speed"]),
                (VEL, w.velocity),
                1,
            );
            if num(&t["speed"]) > 0.0 || t["role"] != "dynamic" {
                self.angle(
                    &format!("{who}.theta"),
                    num(&o["theta"]),
                    num(&t["theta"]),
                    w.heading,
                );
            }
            let id = t["id"].as_u64().expect("id");
            let group_resampled = t["group"]
                .as_u64()
                .is_some_and(|g| resampled_groups.contains(&g));
            if !t["goal"].is_null() && !resampled_humans.contains(&id) && !group_resampled {
                for c in 0..2 {
                    self.close(
                        &format!("{who}.goal[{c}]"),
                        num(&o["goal"][c]),
                        num(&t["goal"][c]),
                        POS,
                        0,
                    );
                }
            }
        }
        let og = ours["groups"].as_array().expect("groups");
        let tg = theirs["groups"].as_array().expect("groups");
        for (k, (o, t)) in og.iter().zip(tg).enumerate() {
            for c in 0..2 {
                self.close(
                    &format!("{at} groups[{k}].centre[{c}]"),
                    num(&o["centre"][c]),
                    num(&t["centre"][c]),
                    POS,
                    0,
                );
                if !t["goal"].is_null() && !resampled_groups.contains(&(k as u64)) {
                    self.close(
                        &format!("{at} groups[{k}].goal[{c}]"),
                        num(&o["goal"][c]),
                        num(&t["goal"][c]),
                        POS,
                        0,
                    );
                }
            }
        }
        let (om, tm) = (&ours["metrics"], &theirs["metrics"]);
        for key in tm.as_object().expect("metrics").keys() {
            if key == "failure_to_progress" {
                self.close(
                    &format!("{at} metrics.{key}"),
                    num(&om[key]),
                    ctx.ftp,
                    0.0,
                    1,
                );
                continue;
            }
            if key == "compliant_count" {
                // F2: one more or one less where a contact flip changed the decision.
                self.close(
                    &format!("{at} metrics.{key}"),
                    num(&om[key]),
                    num(&tm[key]) + ctx.compliant_change,
                    0.0,
                    1,
                );
                continue;
            }
            if let Some(list) = tm[key].as_array() {
                for (c, v) in list.iter().enumerate() {
                    self.close(
                        &format!("{at} metrics.{key}[{c}]"),
                        num(&om[key][c]),
                        num(v),
                        VEL,
                        1,
                    );
                }
            } else {
                let tol = if key.contains("distance") || key.contains("length") {
                    POS
                } else {
                    VEL
                };
                self.close(
                    &format!("{at} metrics.{key}"),
                    num(&om[key]),
                    num(&tm[key]),
                    tol,
                    1,
                );
            }
        }
        let (or, tr) = (&ours["reward_state"], &theirs["reward_state"]);
        self.close(
            &format!("{at} reward_state.prev_distance"),
            num(&or["prev_distance"]),
            num(&tr["prev_distance"]),
            POS,
            0,
        );
        for (key, tol) in [
            ("distance_reward", REWARD),
            ("alive_reward", REWARD),
            ("sngnn_reward", SNGNN),
            ("DISCOMFORT_SNGNN", SNGNN),
        ] {
            self.close(
                &format!("{at} reward_state.info.{key}"),
                num(&or["info"][key]),
                num(&tr["info"][key]),
                tol,
                3,
            );
        }
    }
}

/// What the comparison of one step's outputs and state needs besides the two states.
struct Context<'a> {
    /// The episode's header (walls, human parameters).
    header: &'a Value,
    /// socnav's state after the step.
    ours: &'a Value,
    /// The FAILURE_TO_PROGRESS count socnav must report (`Report::failure_to_progress`).
    ftp: f64,
    /// The time step (s).
    dt: f64,
    /// The step, for messages.
    at: &'a str,
    /// The recorded post-motion state with the contact-flipped humans where socnav put them
    /// ([`with_flipped_from`]); `None` without a contact flip.
    knock_on: Option<&'a Value>,
    /// What the contact flips change in the personal-space compliance count (−1, 0 or 1).
    compliant_change: f64,
    /// The step's tick (0.1.1's `ticks`, the compliance denominator).
    tick: f64,
}

/// Personal-space threshold (m) between the robot's surface and a human's centre: 0.1.1's
/// `(closest_human_dist - ROBOT_RADIUS) >= 0.45` ("same value used in SEAN 2.0").
const PERSONAL_SPACE: f64 = 0.45;

/// 0.1.1's MINIMUM_DISTANCE_TO_HUMAN of a post-motion state: the smallest centre distance from
/// the robot to any human (lone, group member or laptop user), √(dx² + dy²) in f64 as it
/// evaluates it; +∞ without humans.
pub fn minimum_distance_to_human(state: &Value) -> f64 {
    let (rx, ry) = (num(&state["robot"]["x"]), num(&state["robot"]["y"]));
    state["humans"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|h| ((rx - num(&h["x"])).powi(2) + (ry - num(&h["y"])).powi(2)).sqrt())
        .fold(f64::INFINITY, f64::min)
}

/// F2, the knock-on of a contact flip: a human whose push-out socnav decided the other way
/// within its bracket ended the step up to one push (≤ max speed·dt) away from where 0.1.1 put
/// it, and every info value computed from it differs by the push, not by rounding. Those values
/// are compared with the recorded formula evaluated on this state: the recorded post-motion
/// state `post` with each flipped human at socnav's position, heading and speed (`ours`), and
/// the centre of a moving group it belongs to at socnav's centre. The reconstructions
/// (`dsrnn_discomfort`, [`minimum_distance_to_human`], the compliance decision,
/// TIME_TO_COLLISION's `state_differences`) are checked against the recording on `post` itself.
pub fn with_flipped_from(post: &Value, ours: &Value, flipped: &[bool]) -> Value {
    let mut state = post.clone();
    let mut moved_groups = Vec::new();
    if let Some(humans) = state["humans"].as_array_mut() {
        for (k, h) in humans.iter_mut().enumerate() {
            if !flipped.get(k).copied().unwrap_or(false) {
                continue;
            }
            let o = &ours["humans"][k];
            for key in ["x", "y", "theta", "speed"] {
                h[key] = o[key].clone();
            }
            if let Some(g) = h["group"].as_u64() {
                moved_groups.push(g as usize);
            }
        }
    }
    for g in moved_groups {
        if let Some(centre) = ours["groups"].get(g).map(|o| o["centre"].clone()) {
            state["groups"][g]["centre"] = centre;
        }
    }
    state
}

/// How the state comparison of one step is widened or restricted.
struct StateWidening<'a> {
    /// The shadow robot's velocity conditioning.
    shadow: Widen,
    /// Each human's velocity conditioning (observation order).
    humans: &'a [Widen],
    /// Humans left out (contact decided differently within the 64-gon margin).
    flipped: &'a [bool],
    /// The shadow robot's `collided` flag socnav must report.
    shadow_collided: bool,
}

/// How far socnav's inputs to human `k`'s time-to-collision test are from the recorded ones:
/// the measured differences of the robot's and the human's positions (m) and velocities (m/s;
/// a velocity speed·(cos θ, sin θ) moves by |Δspeed| + speed·|Δθ|). The state comparison
/// bounds these separately.
fn state_differences(ours: &Value, theirs: &Value, k: usize) -> Perturbation {
    let angle = |a: f64, b: f64| (a - b).sin().atan2((a - b).cos()).abs();
    let position =
        |o: &Value, t: &Value| (num(&o["x"]) - num(&t["x"])).hypot(num(&o["y"]) - num(&t["y"]));
    let (or, tr) = (&ours["robot"], &theirs["robot"]);
    let command = num(&tr["vel"][0]).hypot(num(&tr["vel"][1]));
    let robot_velocity = (num(&or["vel"][0]) - num(&tr["vel"][0]))
        .hypot(num(&or["vel"][1]) - num(&tr["vel"][1]))
        + command * angle(num(&or["theta"]), num(&tr["theta"]));
    let (oh, th) = (&ours["humans"][k], &theirs["humans"][k]);
    if !oh.is_object() || !th.is_object() {
        return Perturbation {
            position: f64::INFINITY,
            velocity: f64::INFINITY,
        };
    }
    let speed = num(&th["speed"]);
    Perturbation {
        position: position(or, tr) + position(oh, th),
        velocity: robot_velocity
            + (num(&oh["speed"]) - speed).abs()
            + speed * angle(num(&oh["theta"]), num(&th["theta"])),
    }
}
