//! `socnav render` (drawing lands in `socnav::render`).

use crate::args::RenderArgs;

pub fn render(_a: &RenderArgs) -> Result<(), Box<dyn std::error::Error>> {
    Err("rendering is not built yet".into())
}
