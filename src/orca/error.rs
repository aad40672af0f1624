//! Errors a caller of the ORCA module can cause (bad obstacles, bad agent parameters).

/// Why an ORCA input was rejected.
///
/// Indices refer to the caller's input order: `polygon` indexes the polygon list, `vertex` the
/// vertex inside that polygon, `agent` the agent list.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum OrcaError {
    /// A polygon needs at least 2 vertices (2 vertices make a two-sided segment).
    #[error("obstacle polygon {polygon} has {count} vertices; at least 2 are needed")]
    TooFewVertices {
        /// Index of the polygon.
        polygon: usize,
        /// Number of vertices it has.
        count: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("obstacle polygon {polygon} vertex {vertex} is not finite: ({x}, {y})")]
    NonFiniteVertex {
        /// Index of the polygon.
        polygon: usize,
        /// Index of the vertex inside the polygon.
        vertex: usize,
        /// x coordinate (m).
        x: f32,
        /// y coordinate (m).
        y: f32,
    },
    /// An agent or scene parameter is outside its valid range.
    #[error("invalid {name} = {value}{}: {reason}", agent_suffix(*.agent))]
    InvalidParameter {
        /// Index of the agent, or `None` for a scene-level parameter (the time step).
        agent: Option<usize>,
        /// Parameter name, as spelled in [`crate::orca::OrcaAgent`] or [`crate::orca::Scene`].
        name: &'static str,
        /// The rejected value.
        value: f32,
        /// The rule it breaks.
        reason: &'static str,
    },
}

fn agent_suffix(agent: Option<usize>) -> String {
    agent.map_or_else(String::new, |i| format!(" of agent {i}"))
}
