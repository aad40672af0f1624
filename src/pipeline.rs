//! The step, declared once: [`STAGES`] lists the stages in the reference's order (spec 4.1,
//! DESIGN.md section 3), each with its CPU function and what runs it on the GPU. The CPU backend
//! runs them in this order over chunks of environments; the GPU backend encodes one pass per
//! entry, named after it, from the same list. Adding a stage means adding one entry here (and
//! its `src/systems/<name>.rs` / `shaders/<name>.wgsl` pair).

use crate::params::StepParams;
use crate::systems;

// `Batch`, the stages' argument, is defined with the stages, which sit below this list of them.
pub use crate::systems::Batch;

/// One stage of the step: a function over one environment of a batch, and its shader
/// `shaders/<name>.wgsl`.
#[derive(Debug, Clone, Copy)]
pub struct Stage {
    /// Name, shared with the stage's source files and GPU pass label.
    pub name: &'static str,
    /// The CPU implementation.
    pub run: fn(&StepParams, &mut Batch<'_>, usize),
    /// How the GPU backend runs `shaders/<name>.wgsl`.
    pub shader: Shader,
    /// Whether the stage does anything only with the SNGNN-v2 reward. The CPU function returns
    /// at once otherwise; the GPU backend then has no buffers for it and leaves it out of the
    /// step.
    pub sngnn_reward_only: bool,
}

/// How the GPU backend runs a stage's shader.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shader {
    /// Compiled with the batch prelude (`backend::wgsl::prelude`): one dispatch over the
    /// environments, one invocation each.
    Batch,
    /// SNGNN-v2's network: bindings of its own, no batch prelude
    /// (`backend::wgsl::assemble_standalone`), dispatched by `backend::gpu::GpuNet` over the
    /// packed graphs.
    Network,
}

impl Stage {
    /// The stage's shader file under `shaders/`.
    pub fn shader_file(&self) -> String {
        format!("{}.wgsl", self.name)
    }
}

/// The stage named `name`, if the step has one.
pub fn stage(name: &str) -> Option<&'static Stage> {
    STAGES.iter().find(|s| s.name == name)
}

/// A stage that every step runs, as a batch shader on the GPU.
const fn every_step(name: &'static str, run: fn(&StepParams, &mut Batch<'_>, usize)) -> Stage {
    Stage {
        name,
        run,
        shader: Shader::Batch,
        sngnn_reward_only: false,
    }
}

/// The stages of a step, in order.
pub const STAGES: [Stage; 17] = [
    every_step("begin_step", systems::begin_step::begin_step),
    every_step("robot_motion", systems::robot_motion::robot_motion),
    every_step("shadow_robot", systems::shadow_robot::shadow_robot),
    every_step(
        "group_velocities",
        systems::group_velocities::group_velocities,
    ),
    every_step("human_motion", systems::human_motion::human_motion),
    every_step("group_motion", systems::group_motion::group_motion),
    every_step("goals", systems::goals::goals),
    every_step("formation", systems::formation::formation),
    every_step("contacts", systems::contacts::contacts),
    every_step("termination", systems::termination::termination),
    Stage {
        name: "sngnn_graph",
        run: systems::sngnn_graph::sngnn_graph,
        shader: Shader::Batch,
        sngnn_reward_only: true,
    },
    Stage {
        name: "sngnn_score",
        run: systems::sngnn_score::sngnn_score,
        shader: Shader::Network,
        sngnn_reward_only: true,
    },
    every_step("reward", systems::reward::reward),
    every_step("metrics", systems::metrics::metrics),
    every_step("observation", systems::observation::observation),
    every_step("social_events", systems::social_events::social_events),
    every_step("autoreset", systems::autoreset::autoreset),
];
