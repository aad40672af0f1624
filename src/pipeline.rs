//! The step, declared once: [`STAGES`] lists the stages in the reference's order (docs/spec.md 4.1;
//! docs/spec.md, step and autoreset), each with its CPU function and its GPU plan ([`GpuPlan`]: the
//! pass it runs in, fused with its neighbours or alone; whether its rare work is queued out of the
//! hot pass; whether it regroups or resets environments, leaving ORCA obstacles to rebuild). The
//! CPU backend runs the stages in this order over chunks of environments; the GPU backend derives
//! its passes, queues and rebuild entry points from the same list (`backend::schedule`). Adding a
//! stage means adding one entry here (and its `src/systems/<name>.rs` / `shaders/<name>.wgsl`
//! pair); a test checks every plan against its shader file.

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
    /// What the GPU backend does with the stage's shader besides dispatching it.
    pub gpu: GpuPlan,
}

/// A stage's plan on the GPU. The backend's schedule is derived from these (`backend::schedule`:
/// the passes, the rare-work queues, the passes that rebuild); the shader files agree with them
/// (`tests/suite/foundations/shaders_validate.rs`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GpuPlan {
    /// The fused pass the stage runs in with its neighbours (its file defines `fn
    /// stage_<name>(e)` and no `main`), or `None`: a pass of its own.
    pub fused: Option<FusedPass>,
    /// The stage's rare work runs out of the hot pass: its shader's second entry point
    /// (`queue_work`) queues the environments with work this step, and `main` runs a lane per
    /// queued environment. The queues are numbered in [`STAGES`] order ([`rare_queue`]).
    pub rare_work: bool,
    /// Its `main` regroups environments (`regroup_canonicalize`), leaving their ORCA obstacles
    /// to the submit's one rebuild dispatch.
    pub regroups: bool,
    /// It resets environments from the reset pool, whose rows may leave their ORCA obstacles to
    /// the device (rebuilt like a regrouping's).
    pub resets: bool,
}

impl GpuPlan {
    /// A pass of its own, nothing queued, regrouped or reset.
    const ALONE: Self = Self {
        fused: None,
        rare_work: false,
        regroups: false,
        resets: false,
    };

    /// The stage's obstacle rebuilds wait for the submit's one rebuild dispatch: it regroups or
    /// resets environments.
    pub const fn queues_rebuilds(&self) -> bool {
        self.regroups || self.resets
    }
}

/// The passes that run several consecutive stages in one dispatch (the light stages cost a
/// dispatch each, about 25 µs on an H100, for a few microseconds of work). Every member works on
/// its own environment only (lane `e` reads and writes environment `e`, no queue, no workgroup
/// memory), so one lane runs the members in order, as the CPU backend runs every stage over a
/// chunk before the next. A member's bit in the pass's member mask is its index among the pass's
/// stages in [`STAGES`] order ([`FusedPass::members`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FusedPass {
    /// The robot's and the walkers' wished velocities: `robot_motion`, `shadow_robot`,
    /// `group_velocities`.
    Motion,
    /// The crowd's motion: `human_motion`, `group_motion`, `goals`.
    Crowd,
    /// The step's outcome: `contacts`, `termination`, `reward`, `metrics`, `observation`
    /// (SNGNN-v2's graph and network, between `termination` and `reward`, run between the pass's
    /// dispatches).
    Outcome,
}

impl FusedPass {
    /// Every fused pass, in the order of their first stages.
    pub const ALL: [FusedPass; 3] = [Self::Motion, Self::Crowd, Self::Outcome];

    /// The pass's name: its GPU pass label and the name of its assembled source.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Motion => "motion",
            Self::Crowd => "crowd",
            Self::Outcome => "outcome",
        }
    }

    /// The pass named `name`, if one is.
    pub fn named(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The pass's stages, in [`STAGES`] order: member `k` has bit `k` of a member mask.
    pub fn members(self) -> impl Iterator<Item = &'static Stage> {
        STAGES.iter().filter(move |s| s.gpu.fused == Some(self))
    }
}

/// The fused pass stage `name` runs in, and its member index there (its bit in a member mask).
pub fn fused_member(name: &str) -> Option<(FusedPass, u32)> {
    let pass = stage(name)?.gpu.fused?;
    let bit = pass.members().position(|s| s.name == name)?;
    Some((pass, bit as u32))
}

/// The rare-work queue of stage `name`: its index among the stages with rare work, in [`STAGES`]
/// order; `None` for a stage without.
pub fn rare_queue(name: &str) -> Option<usize> {
    STAGES
        .iter()
        .filter(|s| s.gpu.rare_work)
        .position(|s| s.name == name)
}

/// The stages with rare work ([`GpuPlan::rare_work`]): as many queues (and one more, for the
/// rebuilds).
pub const RARE_WORK_STAGES: usize = {
    let mut n = 0;
    let mut k = 0;
    while k < STAGES.len() {
        if STAGES[k].gpu.rare_work {
            n += 1;
        }
        k += 1;
    }
    n
};

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

/// A stage that every step runs, as a batch shader of its own on the GPU.
const fn every_step(name: &'static str, run: fn(&StepParams, &mut Batch<'_>, usize)) -> Stage {
    Stage {
        name,
        run,
        shader: Shader::Batch,
        sngnn_reward_only: false,
        gpu: GpuPlan::ALONE,
    }
}

/// A stage that every step runs as a member of fused pass `pass` on the GPU.
const fn fused(
    pass: FusedPass,
    name: &'static str,
    run: fn(&StepParams, &mut Batch<'_>, usize),
) -> Stage {
    let mut stage = every_step(name, run);
    stage.gpu.fused = Some(pass);
    stage
}

/// A stage that every step runs in a pass of its own, its rare work queued out of the hot pass:
/// resets from the reset pool.
const fn resetting(name: &'static str, run: fn(&StepParams, &mut Batch<'_>, usize)) -> Stage {
    let mut stage = every_step(name, run);
    stage.gpu.rare_work = true;
    stage.gpu.resets = true;
    stage
}

/// A stage that every step runs in a pass of its own, its rare work queued out of the hot pass:
/// regroupings.
const fn regrouping(name: &'static str, run: fn(&StepParams, &mut Batch<'_>, usize)) -> Stage {
    let mut stage = every_step(name, run);
    stage.gpu.rare_work = true;
    stage.gpu.regroups = true;
    stage
}

/// The stages of a step, in order.
pub const STAGES: [Stage; 17] = [
    resetting("begin_step", systems::begin_step::begin_step),
    fused(
        FusedPass::Motion,
        "robot_motion",
        systems::robot_motion::robot_motion,
    ),
    fused(
        FusedPass::Motion,
        "shadow_robot",
        systems::shadow_robot::shadow_robot,
    ),
    fused(
        FusedPass::Motion,
        "group_velocities",
        systems::group_velocities::group_velocities,
    ),
    fused(
        FusedPass::Crowd,
        "human_motion",
        systems::human_motion::human_motion,
    ),
    fused(
        FusedPass::Crowd,
        "group_motion",
        systems::group_motion::group_motion,
    ),
    fused(FusedPass::Crowd, "goals", systems::goals::goals),
    regrouping("formation", systems::formation::formation),
    fused(FusedPass::Outcome, "contacts", systems::contacts::contacts),
    fused(
        FusedPass::Outcome,
        "termination",
        systems::termination::termination,
    ),
    Stage {
        name: "sngnn_graph",
        run: systems::sngnn_graph::sngnn_graph,
        shader: Shader::Batch,
        sngnn_reward_only: true,
        gpu: GpuPlan::ALONE,
    },
    Stage {
        name: "sngnn_score",
        run: systems::sngnn_score::sngnn_score,
        shader: Shader::Network,
        sngnn_reward_only: true,
        gpu: GpuPlan::ALONE,
    },
    fused(FusedPass::Outcome, "reward", systems::reward::reward),
    fused(FusedPass::Outcome, "metrics", systems::metrics::metrics),
    fused(
        FusedPass::Outcome,
        "observation",
        systems::observation::observation,
    ),
    regrouping("social_events", systems::social_events::social_events),
    resetting("autoreset", systems::autoreset::autoreset),
];
