//! The step, declared once: [`STAGES`] lists the stages in the reference's order (spec 4.1,
//! DESIGN.md section 3). The CPU backend runs them in this order over chunks of environments; the
//! GPU backend encodes one compute pass per entry, named after it. Adding a stage means adding
//! one entry here (and its `src/systems/<name>.rs` / `shaders/<name>.wgsl` pair).

use crate::error::SimError;
use crate::outputs::OutChunk;
use crate::params::StepParams;
use crate::sngnn::Scorer;
use crate::state::StateChunk;
use crate::systems;

/// Everything a stage reads and writes for a contiguous range of environments.
#[derive(Debug)]
pub struct Batch<'a> {
    /// State of the environments.
    pub s: StateChunk<'a>,
    /// Their outputs.
    pub o: OutChunk<'a>,
    /// Their actions: 3 floats per environment in [-1, 1] (forward, lateral, rotation), already
    /// validated at the API boundary.
    pub actions: &'a [f32],
    /// The SNGNN-v2 scorer, when the reward is SNGNN-v2's (shared, read-only).
    pub sngnn: Option<&'a Scorer>,
    /// The first error a stage met (only resets can fail: an unsatisfiable scenario).
    pub error: Option<SimError>,
}

impl<'a> Batch<'a> {
    /// Split into the first `mid` environments and the rest.
    pub fn split_at(self, mid: usize) -> (Batch<'a>, Batch<'a>) {
        let (s0, s1) = self.s.split_at(mid);
        let (o0, o1) = self.o.split_at(mid);
        // Resets run without actions: both halves then get none.
        let (a0, a1) = if self.actions.is_empty() {
            (self.actions, self.actions)
        } else {
            self.actions.split_at(3 * mid)
        };
        (
            Batch {
                s: s0,
                o: o0,
                actions: a0,
                sngnn: self.sngnn,
                error: None,
            },
            Batch {
                s: s1,
                o: o1,
                actions: a1,
                sngnn: self.sngnn,
                error: self.error,
            },
        )
    }

    /// Number of environments.
    pub fn n_envs(&self) -> usize {
        self.s.n_envs
    }

    /// Batch index of local environment `e` (keys the RNG).
    pub fn env_index(&self, e: usize) -> u32 {
        (self.s.first_env + e) as u32
    }
}

/// One stage of the step: a function over one environment of a batch.
#[derive(Debug, Clone, Copy)]
pub struct Stage {
    /// Name, shared with the stage's source files and GPU pass label.
    pub name: &'static str,
    /// The CPU implementation.
    pub run: fn(&StepParams, &mut Batch<'_>, usize),
}

/// The stages of a step, in order.
pub const STAGES: [Stage; 15] = [
    Stage {
        name: "begin_step",
        run: systems::begin_step::begin_step,
    },
    Stage {
        name: "robot_motion",
        run: systems::robot_motion::robot_motion,
    },
    Stage {
        name: "shadow_robot",
        run: systems::shadow_robot::shadow_robot,
    },
    Stage {
        name: "group_velocities",
        run: systems::group_velocities::group_velocities,
    },
    Stage {
        name: "human_motion",
        run: systems::human_motion::human_motion,
    },
    Stage {
        name: "group_motion",
        run: systems::group_motion::group_motion,
    },
    Stage {
        name: "goals",
        run: systems::goals::goals,
    },
    Stage {
        name: "formation",
        run: systems::formation::formation,
    },
    Stage {
        name: "contacts",
        run: systems::contacts::contacts,
    },
    Stage {
        name: "termination",
        run: systems::termination::termination,
    },
    Stage {
        name: "reward",
        run: systems::reward::reward,
    },
    Stage {
        name: "metrics",
        run: systems::metrics::metrics,
    },
    Stage {
        name: "observation",
        run: systems::observation::observation,
    },
    Stage {
        name: "social_events",
        run: systems::social_events::social_events,
    },
    Stage {
        name: "autoreset",
        run: systems::autoreset::autoreset,
    },
];
