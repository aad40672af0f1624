//! The social events (docs/spec.md 4.5) against SocNavGym 0.1.1 and against their configured rates.
//!
//! * Regrouping: every dispersal and formation start that the golden episodes recorded is
//!   applied, with the recorded decisions (which group, who stays, which walkers, which laptop,
//!   the slots), to the recorded state before the events through the public functions the step
//!   uses; the lists that result (humans in observation order with their roles, groups, laptop
//!   users, laptops, formations in progress) must be the recorded ones. The random parts the
//!   decisions do not fix (new goals of walkers) are left out.
//! * Rates: over many episodes, each event happens as often as its probability says (binomial
//!   bounds), and the counts the step reports agree with what changed in the state.
//! * Invariants: no human is in two places (group member, laptop user, lone) and the numbers of
//!   humans and laptops never change, whatever the events did.

use crate::golden;

use std::collections::BTreeMap;

use golden::{Episode, Step, config_for, golden_dir_or_skip, load_episodes, num};
use serde_json::Value;
use socnav::document;
use socnav::rng::RngStream;
use socnav::scenario::place::Pose;
use socnav::spec::{EVENT_KEYS, event};
use socnav::state::{BatchState, NONE, forming, role};
use socnav::systems::social_events::{
    disperse_group, end_laptop_use, send_to_laptop, start_crowd_formation,
};
use socnav::{Actions, BatchEnv, Config, EnvOptions};

// ---------------------------------------------------------------------------------------------
// Regrouping against the golden episodes
// ---------------------------------------------------------------------------------------------

#[test]
fn recorded_events_regroup_like_0_1_1() {
    let mut applied: BTreeMap<String, usize> = BTreeMap::new();
    let Some(dir) = golden_dir_or_skip("recorded_events_regroup_like_0_1_1") else {
        return;
    };
    for (name, ep) in load_episodes(&dir, None) {
        if ep.config_name().contains("with_sngnn") {
            continue;
        }
        for step in ep.steps() {
            let events = after_observation_events(&step);
            if events.is_empty() {
                continue;
            }
            let at = format!("{name} t={}", step.t());
            let (ours, new_walkers) = apply_recorded(&ep, &step, &events, &at);
            compare_lists(&ours, step.state(), &new_walkers, &at);
            for e in &events {
                *applied
                    .entry(e["type"].as_str().unwrap().to_string())
                    .or_default() += 1;
            }
        }
    }
    println!("applied: {applied:?}");
    for kind in [
        "crowd_dispersal",
        "hl_dispersal",
        "crowd_formation_start",
        "hl_formation_start",
    ] {
        assert!(
            applied.get(kind).copied().unwrap_or(0) > 0,
            "no `{kind}` event in the golden set to check against: {applied:?}"
        );
    }
}

/// The events of the stochastic block at the end of the step, in the order drawn.
fn after_observation_events<'a>(step: &Step<'a>) -> Vec<&'a Value> {
    step.v["events"]
        .as_array()
        .into_iter()
        .flatten()
        .filter(|e| e["phase"] == "after_observation")
        .collect()
}

/// Load the state before the events, apply each recorded event with its decisions, and return
/// the resulting state snapshot and the ids of the humans that became walkers (new random goals).
fn apply_recorded(ep: &Episode, step: &Step<'_>, events: &[&Value], at: &str) -> (Value, Vec<u64>) {
    let config = config_for(ep).unwrap_or_else(|e| panic!("{at}: {e}"));
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs: 1,
            ..Default::default()
        },
    )
    .unwrap();
    env.set_state(0, &ep.document(step.state_after_motion()))
        .unwrap_or_else(|e| panic!("{at}: {e}"));
    let p = *env.params();
    let mut state: BatchState = env.state().unwrap().clone();
    // New walkers' goals come from this stream; their values are not compared.
    let mut rng = RngStream::new(0, 0);
    let mut new_walkers = Vec::new();
    for ev in events {
        // Indices refer to the lists as they are when the event happens.
        let now = document::export(&p, &state, 0)["state"].clone();
        let mut s = state.env_chunk(0);
        match ev["type"].as_str().unwrap() {
            "crowd_dispersal" => {
                let g = ev["group_index"].as_u64().unwrap() as usize;
                let leavers = ids(&ev["to_dynamic"]);
                let members = ids(&now["groups"][g]["members"]);
                assert_eq!(members, ids(&ev["members"]), "{at}: members of group {g}");
                let stays: Vec<bool> = members.iter().map(|m| !leavers.contains(m)).collect();
                let became_standing = ev["became_standing"] == true;
                disperse_group(&p, &mut s, 0, g, &stays, became_standing, &mut rng);
                new_walkers.extend(leavers);
            }
            "hl_dispersal" => {
                let u = ev["hl_index"].as_u64().unwrap() as usize;
                assert_eq!(
                    now["hl_interactions"][u]["human"], ev["human"],
                    "{at}: laptop user {u}"
                );
                end_laptop_use(&p, &mut s, 0, u, &mut rng);
                new_walkers.push(ev["human"].as_u64().unwrap());
            }
            "crowd_formation_start" => {
                let cf = &step.state()["crowd_forming"];
                let slots: Vec<Pose> = cf["slots"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|s| (num(&s[0]) as f32, num(&s[1]) as f32, num(&s[2]) as f32))
                    .collect();
                let mut chosen = vec![NONE; slots.len()];
                for (id, k) in cf["slot_of"].as_object().unwrap() {
                    let id: u64 = id.parse().unwrap();
                    chosen[k.as_u64().unwrap() as usize] = slot_of_human(&now, id, at);
                }
                start_crowd_formation(&mut s, 0, &chosen, &slots);
            }
            // socnav computes the seat and decides whether it is free: both must agree with
            // 0.1.1 (the seat pose is compared with the recorded one below).
            "hl_formation_start" => {
                let h = slot_of_human(&now, ev["human"].as_u64().unwrap(), at);
                let l = slot_of(&now["laptops"], ev["laptop"].as_u64().unwrap(), at);
                assert!(
                    send_to_laptop(&p, &mut s, 0, h, l),
                    "{at}: socnav finds the seat blocked"
                );
            }
            // 0.1.1 does not record the blocked laptop: each free one must then be blocked for
            // this walker (exp2/exp3 have a single laptop).
            "hl_formation_blocked" => {
                let h = slot_of_human(&now, ev["human"].as_u64().unwrap(), at);
                let free: Vec<u32> = now["laptops"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .enumerate()
                    .filter(|(_, l)| l["hl"].is_null())
                    .map(|(k, _)| k as u32)
                    .collect();
                assert_eq!(
                    free.len(),
                    1,
                    "{at}: which laptop was blocked is not recorded"
                );
                assert!(
                    !send_to_laptop(&p, &mut s, 0, h, free[0]),
                    "{at}: socnav finds the seat free"
                );
            }
            other => panic!("{at}: unexpected after-observation event `{other}`"),
        }
    }
    let ours = document::export(&p, &state, 0)["state"].clone();
    (ours, new_walkers)
}

fn ids(v: &Value) -> Vec<u64> {
    v.as_array()
        .into_iter()
        .flatten()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

fn slot_of(list: &Value, id: u64, at: &str) -> u32 {
    list.as_array()
        .unwrap()
        .iter()
        .position(|x| x["id"] == id)
        .unwrap_or_else(|| panic!("{at}: no entity {id}")) as u32
}

fn slot_of_human(state: &Value, id: u64, at: &str) -> u32 {
    slot_of(&state["humans"], id, at)
}

/// The lists and everything the events change, socnav's against 0.1.1's.
fn compare_lists(ours: &Value, theirs: &Value, new_walkers: &[u64], at: &str) {
    let field = |v: &Value, list: &str, key: &str| -> Vec<Value> {
        v[list]
            .as_array()
            .into_iter()
            .flatten()
            .map(|x| x[key].clone())
            .collect()
    };
    for key in [
        "id",
        "role",
        "group",
        "hl",
        "policy",
        "forming_crowd",
        "forming_hl",
    ] {
        assert_eq!(
            field(ours, "humans", key),
            field(theirs, "humans", key),
            "{at}: humans' `{key}` in observation order"
        );
    }
    let (oh, th) = (
        ours["humans"].as_array().unwrap(),
        theirs["humans"].as_array().unwrap(),
    );
    for (o, t) in oh.iter().zip(th) {
        let id = t["id"].as_u64().unwrap();
        for key in ["x", "y", "theta", "speed"] {
            close(&o[key], &t[key], 2e-6, &format!("{at}: human {id} {key}"));
        }
        if !new_walkers.contains(&id) && !t["goal"].is_null() {
            for c in 0..2 {
                close(
                    &o["goal"][c],
                    &t["goal"][c],
                    2e-6,
                    &format!("{at}: human {id} goal"),
                );
            }
        }
    }
    for key in ["kind", "members", "dispersable"] {
        assert_eq!(
            field(ours, "groups", key),
            field(theirs, "groups", key),
            "{at}: groups' `{key}`"
        );
    }
    for (o, t) in ours["groups"]
        .as_array()
        .unwrap()
        .iter()
        .zip(theirs["groups"].as_array().unwrap())
    {
        for c in 0..2 {
            close(
                &o["centre"][c],
                &t["centre"][c],
                2e-6,
                &format!("{at}: group centre"),
            );
            if !t["goal"].is_null() {
                close(
                    &o["goal"][c],
                    &t["goal"][c],
                    2e-6,
                    &format!("{at}: group goal"),
                );
            }
        }
    }
    for key in ["human", "laptop", "dispersable"] {
        assert_eq!(
            field(ours, "hl_interactions", key),
            field(theirs, "hl_interactions", key),
            "{at}: laptop users' `{key}`"
        );
    }
    for key in ["id", "hl"] {
        assert_eq!(
            field(ours, "laptops", key),
            field(theirs, "laptops", key),
            "{at}: laptops' `{key}`"
        );
    }
    let forming = |v: &Value, key: &str| v.get(key).filter(|x| !x.is_null()).cloned();
    let (oc, tc) = (
        forming(ours, "crowd_forming"),
        forming(theirs, "crowd_forming"),
    );
    assert_eq!(oc.is_some(), tc.is_some(), "{at}: crowd forming");
    if let (Some(o), Some(t)) = (oc, tc) {
        assert_eq!(
            o["slot_of"], t["slot_of"],
            "{at}: crowd slots of the walkers"
        );
        for c in 0..2 {
            close(
                &o["centre"][c],
                &t["centre"][c],
                2e-6,
                &format!("{at}: crowd centre"),
            );
        }
    }
    let (ol, tl) = (forming(ours, "hl_forming"), forming(theirs, "hl_forming"));
    assert_eq!(ol.is_some(), tl.is_some(), "{at}: laptop formation");
    if let (Some(o), Some(t)) = (ol, tl) {
        assert_eq!(
            (&o["human"], &o["laptop"]),
            (&t["human"], &t["laptop"]),
            "{at}: laptop formation"
        );
        for c in 0..3 {
            close(
                &o["seat"][c],
                &t["seat"][c],
                2e-6,
                &format!("{at}: laptop seat"),
            );
        }
    }
}

/// Values that went through f32 once (the state is f32, the recording f64).
fn close(ours: &Value, theirs: &Value, tol: f64, what: &str) {
    let (o, t) = (num(ours), num(theirs));
    assert!(
        (o - t).abs() <= tol * t.abs().max(1.0),
        "{what}: ours {o} vs 0.1.1's {t}"
    );
}

// ---------------------------------------------------------------------------------------------
// Rates and invariants over many episodes
// ---------------------------------------------------------------------------------------------

/// Experiment 3 with every event likely enough to be measured in a few thousand env-steps.
fn eventful_config() -> Config {
    let mut c = Config::from_file(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/exp3.toml"),
    )
    .unwrap();
    c.events.crowd_dispersal_probability = 0.05;
    c.events.laptop_dispersal_probability = 0.05;
    c.events.crowd_formation_probability = 0.05;
    c.events.laptop_formation_probability = 0.05;
    c
}

/// What the social-events stage of one environment can do this step, read before the step.
/// Every condition is one that nothing earlier in the step can undo (formations complete only
/// while one is in progress; dispersals only add walkers, groups and free laptops).
#[derive(Clone, Copy)]
struct Chances {
    /// A dispersable group of each kind: a crowd dispersal happens with exactly p.
    both_group_kinds: bool,
    /// A dispersable laptop user: a laptop dispersal happens with exactly p.
    laptop_user: bool,
    /// No formation in progress, at least the largest crowd size of free walkers: a crowd
    /// formation starts or gives up with exactly p.
    crowd_formation: bool,
    /// No formation in progress, a free laptop, a free walker, too few walkers for a crowd
    /// (crowd formation impossible unless a dispersal adds walkers, which the test excludes):
    /// a laptop formation starts or is blocked with exactly p.
    laptop_formation: bool,
}

fn chances(s: &BatchState, e: usize, group_size: [i32; 2]) -> Chances {
    let gb = e * s.strides.groups;
    let kinds = (gb..gb + s.n_groups[e] as usize)
        .filter(|&g| s.g_dispersable[g] != 0)
        .fold([false; 2], |mut k, g| {
            k[s.g_kind[g] as usize] = true;
            k
        });
    let ub = e * s.strides.laptop_users;
    let lb = e * s.strides.laptops;
    let hb = e * s.strides.humans;
    let walkers = (hb..hb + s.n_humans[e] as usize)
        .filter(|&i| s.h_role[i] == role::DYNAMIC && s.h_forming[i] == forming::NONE)
        .count() as i32;
    let free_laptop = (lb..lb + s.n_laptops[e] as usize).any(|l| s.l_user[l] == NONE);
    let idle = s.cf_active[e] == 0 && s.lf_active[e] == 0;
    Chances {
        both_group_kinds: kinds[0] && kinds[1],
        laptop_user: (ub..ub + s.n_laptop_users[e] as usize).any(|u| s.lu_dispersable[u] != 0),
        crowd_formation: idle && walkers >= group_size[1],
        laptop_formation: idle && free_laptop && walkers >= 1 && walkers < group_size[0],
    }
}

/// Bernoulli trials of one event kind: (trials, hits).
#[derive(Default)]
struct Tally(u64, u64);

impl Tally {
    fn add(&mut self, eligible: bool, hits: u32) {
        if eligible {
            self.0 += 1;
            self.1 += u64::from(hits);
        }
    }
}

#[test]
fn event_rates_match_the_configured_probabilities() {
    let config = eventful_config();
    let probability = [
        config.events.crowd_dispersal_probability,
        config.events.laptop_dispersal_probability,
        config.events.crowd_formation_probability,
        config.events.laptop_formation_probability,
    ];
    let group_size = config.counts.group_size;
    let n = 256;
    let mut env = BatchEnv::new(
        config,
        EnvOptions {
            n_envs: n,
            seed: 7,
            ..Default::default()
        },
    )
    .unwrap();
    // Random actions: the robot wanders, episodes end and restart now and then.
    let mut rng = RngStream::new(99, 0);
    let mut tallies: [Tally; 4] = Default::default();
    for t in 0..600 {
        let before: Vec<Chances> = (0..n)
            .map(|e| chances(env.state().unwrap(), e, group_size))
            .collect();
        let counts_before = counts(env.state().unwrap());
        let actions: Vec<f32> = (0..n * 3)
            .map(|k| {
                if k % 3 == 1 {
                    0.0
                } else {
                    rng.uniform(-1.0, 1.0)
                }
            })
            .collect();
        env.step(Actions::Continuous(&actions)).unwrap();
        let out = env.outputs();
        let k = EVENT_KEYS.len();
        for (e, c) in before.iter().enumerate() {
            // A step that ends the episode skips the events.
            if out.terminated[e] != 0 || out.truncated[e] != 0 {
                continue;
            }
            let ev = &out.events[e * k..(e + 1) * k];
            let dispersed = ev[event::CROWD_DISPERSAL] + ev[event::LAPTOP_DISPERSAL] > 0;
            tallies[0].add(c.both_group_kinds, ev[event::CROWD_DISPERSAL]);
            tallies[1].add(c.laptop_user, ev[event::LAPTOP_DISPERSAL]);
            tallies[2].add(
                c.crowd_formation,
                ev[event::CROWD_FORMATION_START] + ev[event::CROWD_FORMATION_GAVE_UP],
            );
            tallies[3].add(
                c.laptop_formation && !dispersed,
                ev[event::LAPTOP_FORMATION_START] + ev[event::LAPTOP_FORMATION_BLOCKED],
            );
        }
        // Same episode, same numbers of humans and laptops.
        let counts_after = counts(env.state().unwrap());
        for e in 0..n {
            if counts_before[e].0 == counts_after[e].0 {
                assert_eq!(
                    counts_before[e], counts_after[e],
                    "env {e} step {t}: humans and laptops"
                );
            }
        }
        if t % 20 == 0 {
            check_invariants(&env);
        }
    }
    let names = [
        "crowd dispersal",
        "laptop dispersal",
        "crowd formation",
        "laptop formation",
    ];
    for ((name, tally), p) in names.iter().zip(&tallies).zip(probability) {
        assert_binomial(name, tally.1, tally.0, f64::from(p));
    }
}

/// (episode, humans, laptops) of every environment.
fn counts(s: &BatchState) -> Vec<(u32, u32, u32)> {
    (0..s.n_envs)
        .map(|e| (s.episode[e], s.n_humans[e], s.n_laptops[e]))
        .collect()
}

/// `hits` out of `trials` Bernoulli(p) draws: within 5 standard deviations (a false alarm
/// once in ~3.5 million runs), and enough trials to mean something.
fn assert_binomial(what: &str, hits: u64, trials: u64, p: f64) {
    assert!(trials >= 2000, "{what}: only {trials} trials");
    let mean = trials as f64 * p;
    let sd = (trials as f64 * p * (1.0 - p)).sqrt();
    println!("{what}: {hits} in {trials} (expected {mean:.1} ± {sd:.1})");
    assert!(
        (hits as f64 - mean).abs() <= 5.0 * sd,
        "{what}: {hits} events in {trials} trials, expected {mean:.1} ± {:.1} (5 sd)",
        5.0 * sd
    );
}

/// Every human in exactly one place (lone, one group, one laptop), each laptop used once.
fn check_invariants(env: &BatchEnv) {
    for e in 0..env.n_envs() {
        let doc = env.get_state(e).unwrap();
        let st = &doc["state"];
        let humans = st["humans"].as_array().unwrap();
        let mut places: BTreeMap<u64, u32> = humans
            .iter()
            .map(|h| (h["id"].as_u64().unwrap(), 0))
            .collect();
        assert_eq!(
            places.len(),
            humans.len(),
            "env {e}: a human id twice in the list"
        );
        let mut place = |id: u64| *places.get_mut(&id).expect("a listed human") += 1;
        for g in st["groups"].as_array().unwrap() {
            ids(&g["members"]).into_iter().for_each(&mut place);
        }
        for u in st["hl_interactions"].as_array().unwrap() {
            place(u["human"].as_u64().unwrap());
        }
        for h in humans {
            let id = h["id"].as_u64().unwrap();
            let grouped = !(h["role"] == "static" || h["role"] == "dynamic");
            assert_eq!(
                places[&id],
                u32::from(grouped),
                "env {e}: human {id} ({}) is in {} groups or laptops",
                h["role"],
                places[&id]
            );
        }
        let mut used: Vec<u64> = st["hl_interactions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|u| u["laptop"].as_u64().unwrap())
            .collect();
        let n = used.len();
        used.sort_unstable();
        used.dedup();
        assert_eq!(used.len(), n, "env {e}: a laptop used twice");
    }
}
