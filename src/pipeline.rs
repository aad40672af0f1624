//! The step, declared once: [`STAGES`] lists the stages in the reference's order (spec 4.1,
//! DESIGN.md section 3). The CPU backend runs them in this order over chunks of environments; the
//! GPU backend encodes one compute pass per entry, named after it. Adding a stage means adding
//! one entry here (and its `src/systems/<name>.rs` / `shaders/<name>.wgsl` pair).

use crate::params::StepParams;
use crate::systems;

// `Batch`, the stages' argument, is defined with the stages, which sit below this list of them.
pub use crate::systems::Batch;

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
