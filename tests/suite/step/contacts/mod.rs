//! Stage `contacts` (`src/systems/contacts.rs`, `shaders/contacts.wgsl`): `[model]
//! contact_shape` and its 64-gons against shapely (`shape`, which also covers the robot's and the
//! shadow robot's collisions decided with that shape).

mod shape;
