//! Stage `contacts` (`src/systems/contacts.rs`, `shaders/contacts.wgsl`): the push-out,
//! hand-computed (`cpu`); `[model] contact_shape` and its 64-gons against shapely (`shape`, which
//! also covers the robot's and the shadow robot's collisions decided with that shape); and CPU/GPU
//! parity (`gpu`, with the polygon64 collisions of `termination`).

mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
mod shape;
