//! The stages of the step, one file each (named in [`crate::pipeline::STAGES`]), plus the shared
//! pieces they use: world queries, the ORCA glue, the social force model and resets.

pub mod autoreset;
pub mod begin_step;
pub mod contacts;
pub mod goals;
pub mod group_motion;
pub mod group_velocities;
pub mod human_motion;
pub mod metrics;
pub mod observation;
pub mod orca_obstacles;
pub mod orca_world;
pub mod reset;
pub mod reward;
pub mod robot_motion;
pub mod sfm;
pub mod shadow_robot;
pub mod termination;
pub mod world;
