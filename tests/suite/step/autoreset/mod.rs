//! Stage `autoreset` (`src/systems/autoreset.rs`, `shaders/autoreset.wgsl`): the three
//! autoreset modes through the public API (`cpu`).

mod cpu;
