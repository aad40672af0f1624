//! The bind groups of a batch's passes, declared once: the prelude writes their WGSL
//! declarations from these tables ([`declarations`]) and the GPU backend binds its buffers in the
//! tables' order, by name (`backend::gpu::build`). A binding's number is its index in its table.

/// How the passes see a binding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// A storage buffer the passes only read.
    Read,
    /// A storage buffer the passes read and write.
    ReadWrite,
    /// A uniform buffer.
    Uniform,
    /// A uniform buffer bound at an offset given with each dispatch.
    DynamicUniform,
}

/// One binding of a bind group: its name in WGSL, its access and its WGSL type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BindingDecl {
    /// The variable's name in the shaders (and the buffer's, in the backend).
    pub name: &'static str,
    /// How the passes see it.
    pub access: Access,
    /// Its WGSL type.
    pub ty: &'static str,
}

const fn binding(name: &'static str, access: Access, ty: &'static str) -> BindingDecl {
    BindingDecl { name, access, ty }
}

/// Bind group 0 of every pass compiled with the batch prelude: the step parameters, the state's
/// f32 and u32 columns, the actions, the outputs' f32 and u32 columns, the reset pool, the batch
/// layout, the scratch regions, the rare-work queues and a fused pass's member mask.
pub const BATCH_BINDINGS: [BindingDecl; 11] = [
    binding("params", Access::Read, "StepParams"),
    binding("sf", Access::ReadWrite, "array<f32>"),
    binding("su", Access::ReadWrite, "array<u32>"),
    binding("actions", Access::Read, "array<f32>"),
    binding("outf", Access::ReadWrite, "array<f32>"),
    binding("outu", Access::ReadWrite, "array<u32>"),
    binding("pool", Access::Read, "array<u32>"),
    binding("batch", Access::Uniform, "BatchLayout"),
    binding("scratch", Access::ReadWrite, "array<u32>"),
    binding("rare", Access::ReadWrite, "RareWork"),
    binding("pass_members", Access::DynamicUniform, "vec4<u32>"),
];

/// Bind group 1 of the passes of a batch with the SNGNN-v2 reward (`sngnn_prelude`): every
/// environment's packed graph (u32 and f32 words) and the frame gaps.
pub const SNGNN_GRAPH_BINDINGS: [BindingDecl; 3] = [
    binding("sn_gu", Access::ReadWrite, "array<u32>"),
    binding("sn_gf", Access::ReadWrite, "array<f32>"),
    binding("sn_gaps", Access::Read, "array<u32>"),
];

/// The WGSL declarations of bind group `group` with the bindings of `table`, numbered by index.
pub fn declarations(group: u32, table: &[BindingDecl]) -> String {
    (0u32..)
        .zip(table)
        .map(|(k, b)| {
            let space = match b.access {
                Access::Read => "<storage, read>",
                Access::ReadWrite => "<storage, read_write>",
                Access::Uniform | Access::DynamicUniform => "<uniform>",
            };
            format!(
                "@group({group}) @binding({k}) var{space} {}: {};\n",
                b.name, b.ty
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The declarations number the bindings by index, with each access's address space.
    #[test]
    fn declarations_number_the_table() {
        let text = declarations(1, &SNGNN_GRAPH_BINDINGS);
        assert_eq!(
            text,
            "@group(1) @binding(0) var<storage, read_write> sn_gu: array<u32>;\n\
             @group(1) @binding(1) var<storage, read_write> sn_gf: array<f32>;\n\
             @group(1) @binding(2) var<storage, read> sn_gaps: array<u32>;\n"
        );
        let batch = declarations(0, &BATCH_BINDINGS);
        assert!(batch.contains("@group(0) @binding(7) var<uniform> batch: BatchLayout;\n"));
        assert!(batch.contains("@group(0) @binding(9) var<storage, read_write> rare: RareWork;\n"));
    }
}
