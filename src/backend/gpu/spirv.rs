//! The SPIR-V this backend hands a Vulkan driver: naga's, written with the options wgpu uses,
//! except that the ORCA solver's working lists are not zeroed at every call and no float product
//! and sum may be fused.
//!
//! WGSL gives every function-scope `var` without an initialiser the value zero, and naga's
//! SPIR-V writer spells that as a zero initialiser on the variable, so a function clears its
//! local arrays on every call whether it reads them or not. ORCA's lists are sized for the worst
//! case every shipped config shares (64 agent neighbours, 128 obstacle edges, 192 lines: 4,640
//! bytes an ordinary call), of which a call reads the few entries it filled (issue 19, item 2;
//! docs/performance.md, "Zeroed working memory"). The shaders never read an entry of those lists
//! past their `len`, and clear the lists' counts themselves where they declare them
//! (`orca_*_clear` in `shaders/common/orca.wgsl`), so the zero initialiser of a function-scope
//! variable whose type is one of [`UNZEROED_TYPES`] is dropped from the module, which leaves the
//! arrays' unwritten entries undefined, as their declarations say.
//!
//! Nor is workgroup memory zeroed, which WGSL also promises and naga spells as a store of zero
//! into every workgroup variable at the start of each workgroup. The shaders' two workgroup
//! arrays are read only where written: the observation's tile (`rows` in
//! `shaders/observation.wgsl` reads the values its lanes stored before the barrier) and the
//! obstacle rebuild's working memory (`backend::wgsl::with_obstacles_in_workgroup`, written
//! before read as in `scratch`, which a test poisons: `GpuPaths::poison_orca_lists`). Zeroing
//! the latter's 16 KiB in every workgroup made llvmpipe take minutes to compile its pipelines.
//!
//! Nor may a driver fuse a float product and a sum into one multiply-add. WGSL lets it, and naga
//! never writes SPIR-V's `NoContraction` decoration, so a hardware driver may round `a * b + c`
//! once where the CPU backend rounds twice (lavapipe rounds twice). Where the exact result is
//! zero, such as a velocity whose components cancel, the fused form leaves a residual of
//! rounding's size and the CPU's exactly zero, and a heading taken from it (`atan2`) points
//! anywhere. The H100's and H200's parity runs diverged in `h_theta` at such velocities
//! (benches/RESULTS.md), of which this is the likeliest cause.
//! Every float product and sum ([`CONTRACTIBLE_OPS`]) is therefore decorated `NoContraction`
//! ([`without_contraction`]), as glslang does for GLSL's `precise`; `SOCNAV_SHADERS=spirv-fma`
//! leaves them undecorated, to measure what that costs a device ([`Contraction`]).
//!
//! On Vulkan (lavapipe included), through wgpu's `PASSTHROUGH_SHADERS`, the pipelines are built
//! from this SPIR-V unless `SOCNAV_SHADERS=wgsl` ([`super::SHADERS_VAR`]); elsewhere from the
//! WGSL, as wgpu compiles it. On lavapipe the results are the same: only entries that are
//! written before they are read differ in what they hold at the start, and lavapipe fuses no
//! multiply-add either way.
//!
//! The bounds checks are wgpu's: every index of a local or uniform array clamped, and the
//! indices of storage buffers clamped unless the device enabled `robustBufferAccess2`, which
//! makes an access out of bounds read zero and write nothing ([`BufferBounds`]). Clamping them
//! everywhere, as this module once did, costs llvmpipe dearly wherever a stage's body is a
//! called function (docs/performance.md, "Fused passes").

use std::borrow::Cow;

use naga::back::spv;

/// Struct types whose function-scope variables are not zeroed (see the module docs): a count
/// the declaring function clears and entries read only below it.
pub(crate) const UNZEROED_TYPES: [&str; 3] =
    ["OrcaAgentNeighbors", "OrcaObstacleNeighbors", "OrcaLines"];

/// Who keeps storage-buffer accesses in bounds: the shader, clamping each index to the buffer's
/// length (naga's `BoundsCheckPolicy::Restrict`), or the driver (`Unchecked`), as wgpu decides
/// for its own SPIR-V: the driver where the device enabled `robustBufferAccess2`
/// (`GpuDevice::driver_checks_buffers`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum BufferBounds {
    /// Every storage-buffer index clamped in the shader.
    Clamped,
    /// Left to the driver's `robustBufferAccess2`.
    Driver,
}

/// Whether a driver may fuse a float product and a sum into one multiply-add (see the module
/// docs): WGSL lets it, and naga's SPIR-V says nothing against it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Contraction {
    /// Every float product and sum decorated `NoContraction`: each rounds on its own, as on the
    /// CPU (the default).
    Forbidden,
    /// As naga writes it: the driver may fuse them (`SOCNAV_SHADERS=spirv-fma`, to measure what
    /// forbidding it costs).
    Allowed,
}

/// SPIR-V opcodes, the storage class and the decoration this module reads or writes.
const OP_SOURCE_CONTINUED: u32 = 2;
const OP_SOURCE: u32 = 3;
const OP_SOURCE_EXTENSION: u32 = 4;
const OP_NAME: u32 = 5;
const OP_MEMBER_NAME: u32 = 6;
const OP_STRING: u32 = 7;
const OP_EXTENSION: u32 = 10;
const OP_EXT_INST_IMPORT: u32 = 11;
const OP_MEMORY_MODEL: u32 = 14;
const OP_ENTRY_POINT: u32 = 15;
const OP_EXECUTION_MODE: u32 = 16;
const OP_CAPABILITY: u32 = 17;
const OP_TYPE_POINTER: u32 = 32;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MODULE_PROCESSED: u32 = 330;
const OP_EXECUTION_MODE_ID: u32 = 331;
const STORAGE_CLASS_FUNCTION: u32 = 7;
const DECORATION_NO_CONTRACTION: u32 = 42;
/// Words of the module header before the first instruction.
const HEADER_WORDS: usize = 5;

/// The float instructions a driver could fuse into a multiply-add: the sums and differences
/// (`OpFAdd`, `OpFSub`) and every product (`OpFMul`, `OpVectorTimesScalar`, the matrix products,
/// `OpDot`). Each has its result type and result id as its first two operands.
pub(crate) const CONTRACTIBLE_OPS: [u32; 9] = [129, 131, 133, 142, 143, 144, 145, 146, 148];

/// The instructions of a module's sections before its annotations (SPIR-V's logical layout,
/// section 2.4: capabilities to the debug names), after which a decoration may stand.
const BEFORE_ANNOTATIONS: [u32; 14] = [
    OP_CAPABILITY,
    OP_EXTENSION,
    OP_EXT_INST_IMPORT,
    OP_MEMORY_MODEL,
    OP_ENTRY_POINT,
    OP_EXECUTION_MODE,
    OP_EXECUTION_MODE_ID,
    OP_STRING,
    OP_SOURCE_EXTENSION,
    OP_SOURCE,
    OP_SOURCE_CONTINUED,
    OP_NAME,
    OP_MEMBER_NAME,
    OP_MODULE_PROCESSED,
];

/// The SPIR-V of entry point `entry` of compute shader `source` (WGSL), with the function-scope
/// variables of [`UNZEROED_TYPES`] not zeroed and, where `contraction` forbids it, every float
/// product and sum decorated `NoContraction`. The error names what failed (parse, validation or
/// the writer) in naga's words.
pub(crate) fn compute_spirv(
    source: &str,
    entry: &str,
    buffers: BufferBounds,
    contraction: Contraction,
) -> Result<Vec<u32>, String> {
    let words = naga_spirv(source, Some(entry), buffers)?;
    let words = without_zero_initialisers(&words, &UNZEROED_TYPES);
    Ok(match contraction {
        Contraction::Forbidden => without_contraction(&words),
        Contraction::Allowed => words,
    })
}

/// naga's SPIR-V of WGSL `source` as it writes it, zero initialisers included: of entry point
/// `entry` alone, or of every entry point when `None`.
fn naga_spirv(
    source: &str,
    entry: Option<&str>,
    buffers: BufferBounds,
) -> Result<Vec<u32>, String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("WGSL parse: {}", e.emit_to_string(source)))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| format!("WGSL validation: {}", e.emit_to_string(source)))?;
    let pipeline = entry.map(|entry| spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: entry.to_owned(),
    });
    spv::write_vec(&module, &info, &writer_options(buffers), pipeline.as_ref())
        .map_err(|e| format!("SPIR-V writer: {e}"))
}

/// The options of wgpu's Vulkan backend that bear on a compute shader (wgpu-hal's
/// `naga_options` with its default runtime checks): array indices clamped, storage-buffer
/// indices clamped unless the driver checks them (`buffers`), loops bounded; except that
/// workgroup memory is not zeroed (see the module docs). `DEBUG` names the types, which is how
/// [`without_zero_initialisers`] finds the variables.
fn writer_options(buffers: BufferBounds) -> spv::Options<'static> {
    let clamp = naga::proc::BoundsCheckPolicy::Restrict;
    spv::Options {
        lang_version: (1, 3),
        flags: spv::WriterFlags::DEBUG,
        bounds_check_policies: naga::proc::BoundsCheckPolicies {
            index: clamp,
            buffer: match buffers {
                BufferBounds::Clamped => clamp,
                BufferBounds::Driver => naga::proc::BoundsCheckPolicy::Unchecked,
            },
            image_load: clamp,
            binding_array: naga::proc::BoundsCheckPolicy::Unchecked,
        },
        zero_initialize_workgroup_memory: spv::ZeroInitializeWorkgroupMemoryMode::None,
        force_loop_bounding: true,
        ..spv::Options::default()
    }
}

/// One instruction of a SPIR-V module: its opcode and its operand words.
struct Instruction<'a> {
    opcode: u32,
    operands: &'a [u32],
}

/// The instructions of module `words` after its header, in order.
fn instructions(words: &[u32]) -> impl Iterator<Item = Instruction<'_>> {
    let mut at = HEADER_WORDS.min(words.len());
    std::iter::from_fn(move || {
        let first = *words.get(at)?;
        let count = ((first >> 16) as usize).max(1);
        let end = (at + count).min(words.len());
        let inst = Instruction {
            opcode: first & 0xffff,
            operands: &words[at + 1..end],
        };
        at = end;
        Some(inst)
    })
}

/// The string of an `OpName`'s operands (after the target id): nul-terminated UTF-8.
fn literal_string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    String::from_utf8_lossy(&bytes[..end]).into_owned()
}

/// A function-scope variable of a module: its result id, the name of its type (empty when the
/// type has none) and whether it has an initialiser.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct FunctionVariable {
    pub id: u32,
    pub type_name: String,
    pub initialised: bool,
}

/// Every function-scope variable of module `words`, in order.
pub(crate) fn function_variables(words: &[u32]) -> Vec<FunctionVariable> {
    let mut names = std::collections::HashMap::new();
    let mut pointee = std::collections::HashMap::new();
    let mut out = Vec::new();
    for inst in instructions(words) {
        match (inst.opcode, inst.operands) {
            (OP_NAME, [target, rest @ ..]) => {
                names.insert(*target, literal_string(rest));
            }
            (OP_TYPE_POINTER, [id, _class, ty]) => {
                pointee.insert(*id, *ty);
            }
            (OP_VARIABLE, [ty, id, STORAGE_CLASS_FUNCTION, init @ ..]) => {
                let type_name = pointee
                    .get(ty)
                    .and_then(|t| names.get(t))
                    .cloned()
                    .unwrap_or_default();
                out.push(FunctionVariable {
                    id: *id,
                    type_name,
                    initialised: !init.is_empty(),
                });
            }
            _ => {}
        }
    }
    out
}

/// Module `words` with the initialiser dropped from every function-scope variable whose type is
/// named in `types`; every other word as it was.
pub(crate) fn without_zero_initialisers(words: &[u32], types: &[&str]) -> Vec<u32> {
    let strip: std::collections::HashSet<u32> = function_variables(words)
        .into_iter()
        .filter(|v| v.initialised && types.contains(&v.type_name.as_str()))
        .map(|v| v.id)
        .collect();
    let mut out = Vec::with_capacity(words.len());
    out.extend_from_slice(&words[..HEADER_WORDS.min(words.len())]);
    for inst in instructions(words) {
        match (inst.opcode, inst.operands) {
            (OP_VARIABLE, [ty, id, class @ STORAGE_CLASS_FUNCTION, _init])
                if strip.contains(id) =>
            {
                out.extend_from_slice(&[(4 << 16) | OP_VARIABLE, *ty, *id, *class]);
            }
            _ => {
                let count = (inst.operands.len() as u32 + 1) << 16;
                out.push(count | inst.opcode);
                out.extend_from_slice(inst.operands);
            }
        }
    }
    out
}

/// The result ids of module `words`' instructions of [`CONTRACTIBLE_OPS`], in order.
pub(crate) fn contractible_results(words: &[u32]) -> Vec<u32> {
    instructions(words)
        .filter(|i| CONTRACTIBLE_OPS.contains(&i.opcode))
        .filter_map(|i| i.operands.get(1).copied())
        .collect()
}

/// The ids that module `words` decorates `NoContraction`, in order.
#[cfg(test)]
fn no_contraction_ids(words: &[u32]) -> Vec<u32> {
    instructions(words)
        .filter_map(|i| match (i.opcode, i.operands) {
            (OP_DECORATE, [id, DECORATION_NO_CONTRACTION]) => Some(*id),
            _ => None,
        })
        .collect()
}

/// Module `words` with an `OpDecorate %id NoContraction` for the result of each of its
/// [`CONTRACTIBLE_OPS`], placed first among the annotations; every other word as it was (the
/// decorations take no new ids).
pub(crate) fn without_contraction(words: &[u32]) -> Vec<u32> {
    let ids = contractible_results(words);
    let mut out = Vec::with_capacity(words.len() + 3 * ids.len());
    out.extend_from_slice(&words[..HEADER_WORDS.min(words.len())]);
    let mut decorated = false;
    for inst in instructions(words) {
        if !decorated && !BEFORE_ANNOTATIONS.contains(&inst.opcode) {
            for &id in &ids {
                out.extend_from_slice(&[(3 << 16) | OP_DECORATE, id, DECORATION_NO_CONTRACTION]);
            }
            decorated = true;
        }
        out.push(((inst.operands.len() as u32 + 1) << 16) | inst.opcode);
        out.extend_from_slice(inst.operands);
    }
    out
}

/// The passthrough descriptor of `spirv` for compute entry point `entry`.
pub(crate) fn passthrough<'a>(
    label: &'a str,
    entry: &'a str,
    workgroup_size: u32,
    spirv: &'a [u32],
) -> wgpu::ShaderModuleDescriptorPassthrough<'a> {
    wgpu::ShaderModuleDescriptorPassthrough {
        label: Some(label),
        entry_points: Cow::Owned(vec![wgpu::PassthroughShaderEntryPoint {
            name: Cow::Borrowed(entry),
            workgroup_size: (workgroup_size, 1, 1),
        }]),
        spirv: Some(Cow::Borrowed(spirv)),
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHADER: &str = "
struct Lines { len: u32, items: array<vec2<f32>, 64> }
struct Other { len: u32, items: array<f32, 8> }
@group(0) @binding(0) var<storage, read_write> out: array<f32>;
fn fill(lines: ptr<function, Lines>, n: u32) {
    (*lines).len = 0u;
    for (var i = 0u; i < n; i++) { (*lines).items[i] = vec2<f32>(f32(i), 1.0); (*lines).len += 1u; }
}
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    var lines: Lines;
    var other: Other;
    fill(&lines, gid.x % 8u);
    other.items[gid.x % 8u] = 2.0;
    out[gid.x] = lines.items[0].x + other.items[0] + f32(lines.len);
}
";

    fn spirv_of(source: &str) -> Vec<u32> {
        naga_spirv(source, None, BufferBounds::Clamped).unwrap()
    }

    fn initialised(words: &[u32], type_name: &str) -> Vec<bool> {
        function_variables(words)
            .into_iter()
            .filter(|v| v.type_name == type_name)
            .map(|v| v.initialised)
            .collect()
    }

    #[test]
    fn naga_zeroes_every_function_scope_struct() {
        let words = spirv_of(SHADER);
        assert_eq!(initialised(&words, "Lines"), [true]);
        assert_eq!(initialised(&words, "Other"), [true]);
    }

    #[test]
    fn only_the_named_types_lose_their_initialiser() {
        let words = spirv_of(SHADER);
        let out = without_zero_initialisers(&words, &["Lines"]);
        assert_eq!(initialised(&out, "Lines"), [false]);
        assert_eq!(initialised(&out, "Other"), [true]);
        // One word fewer per stripped variable, the header and every other instruction kept.
        assert_eq!(out.len(), words.len() - 1);
        assert_eq!(out[..HEADER_WORDS], words[..HEADER_WORDS]);
        let ops = |w: &[u32]| instructions(w).map(|i| i.opcode).collect::<Vec<_>>();
        assert_eq!(ops(&out), ops(&words));
    }

    #[test]
    fn stripping_nothing_changes_nothing() {
        let words = spirv_of(SHADER);
        assert_eq!(without_zero_initialisers(&words, &[]), words);
        assert_eq!(without_zero_initialisers(&words, &["Absent"]), words);
    }

    /// The prelude of a batch of experiment 2.
    fn exp2_prelude() -> String {
        use crate::backend::wgsl;
        let env = crate::BatchEnv::new(
            crate::Config::from_name_or_path("exp2").unwrap(),
            crate::EnvOptions::default(),
        )
        .unwrap();
        let columns = env.state().unwrap().columns();
        wgsl::prelude(
            &columns,
            &env.outputs().columns(),
            &wgsl::SizeClasses::of(&columns),
        )
    }

    /// Pass `pass` (`schedule::passes`) as the GPU backend assembles it for a batch of experiment 2.
    fn exp2_pass(pass: &str) -> String {
        crate::backend::wgsl::assemble_pass(pass, &exp2_prelude()).unwrap()
    }

    #[test]
    fn the_orca_stages_hand_the_driver_their_lists_unzeroed() {
        use crate::backend::schedule;
        let mut orca_passes: Vec<&str> = ["group_velocities", "human_motion", "shadow_robot"]
            .into_iter()
            .map(schedule::pass_of)
            .collect();
        orca_passes.dedup();
        for stage in orca_passes {
            let source = exp2_pass(stage);
            let zeroed = spirv_of(&source);
            let ours = compute_spirv(
                &source,
                "main",
                BufferBounds::Clamped,
                Contraction::Forbidden,
            )
            .unwrap();
            for ty in UNZEROED_TYPES {
                // Each list type is declared (by `orca_world_velocity`, and LP3's lines) and
                // naga zeroes it; the module the driver gets does not.
                assert!(initialised(&zeroed, ty).contains(&true), "{stage}: {ty}");
                let kept = initialised(&ours, ty);
                assert!(
                    !kept.is_empty() && !kept.contains(&true),
                    "{stage}: {ty} {kept:?}"
                );
            }
        }
    }

    #[test]
    fn every_entry_point_of_every_pass_is_written() {
        use crate::backend::{schedule, wgsl};
        let passes = schedule::passes()
            .into_iter()
            .filter(|&p| !schedule::pass_files(p).iter().any(|f| wgsl::needs_sngnn(f)))
            .map(|p| (p.to_owned(), exp2_pass(p)));
        // The passes that reset, as a batch whose pool rows leave their obstacles to the device
        // assembles them.
        let resets = schedule::reset_passes().into_iter().map(|p| {
            let source = wgsl::assemble_pass_rebuilding_resets(p, &exp2_prelude()).unwrap();
            (format!("{p}+rebuild"), source)
        });
        let mut decorated = 0;
        for (file, source) in passes.chain(resets) {
            let module = naga::front::wgsl::parse_str(&source).unwrap();
            for entry in &module.entry_points {
                let words = compute_spirv(
                    &source,
                    &entry.name,
                    BufferBounds::Clamped,
                    Contraction::Forbidden,
                )
                .unwrap_or_else(|e| panic!("{file} {}: {e}", entry.name));
                assert!(
                    function_variables(&words)
                        .iter()
                        .all(|v| !(v.initialised && UNZEROED_TYPES.contains(&v.type_name.as_str()))),
                    "{file} {}",
                    entry.name
                );
                // No product or sum of any pass may be fused by the driver.
                let ids = no_contraction_ids(&words);
                assert_eq!(ids, contractible_results(&words), "{file} {}", entry.name);
                decorated += ids.len();
            }
        }
        // The step's arithmetic: thousands of products and sums (ORCA alone has hundreds).
        assert!(decorated > 5_000, "{decorated}");
    }

    #[test]
    fn naga_leaves_every_product_and_sum_free_to_fuse() {
        let words = spirv_of(SHADER);
        assert!(!contractible_results(&words).is_empty());
        assert!(no_contraction_ids(&words).is_empty());
    }

    #[test]
    fn every_product_and_sum_is_decorated_once_and_nothing_else_changes() {
        let words = spirv_of(SHADER);
        let ids = contractible_results(&words);
        let out = without_contraction(&words);
        assert_eq!(no_contraction_ids(&out), ids);
        assert_eq!(out.len(), words.len() + 3 * ids.len());
        assert_eq!(out[..HEADER_WORDS], words[..HEADER_WORDS]);
        // Without the new decorations, the same instructions in the same order.
        let others = |w: &[u32]| -> Vec<Vec<u32>> {
            instructions(w)
                .filter(|i| {
                    !(i.opcode == OP_DECORATE
                        && i.operands.get(1) == Some(&DECORATION_NO_CONTRACTION))
                })
                .map(|i| [&[i.opcode][..], i.operands].concat())
                .collect()
        };
        assert_eq!(others(&out), others(&words));
    }

    /// naga's own SPIR-V reader, which refuses an instruction out of the module's logical layout
    /// (a decoration among the types, say), reads the decorated module.
    #[test]
    fn the_decorations_stand_where_spirv_puts_annotations() {
        let source = exp2_pass(crate::backend::schedule::pass_of("human_motion"));
        for words in [
            without_contraction(&spirv_of(SHADER)),
            compute_spirv(
                &source,
                "main",
                BufferBounds::Clamped,
                Contraction::Forbidden,
            )
            .unwrap(),
        ] {
            let options = naga::front::spv::Options::default();
            if let Err(e) = naga::front::spv::parse_u8_slice(bytemuck::cast_slice(&words), &options)
            {
                panic!("{e}");
            }
        }
        // Misplaced (after the types), the same decoration is refused.
        let words = spirv_of(SHADER);
        let id = contractible_results(&words)[0];
        let mut late = words.clone();
        late.extend_from_slice(&[(3 << 16) | OP_DECORATE, id, DECORATION_NO_CONTRACTION]);
        let options = naga::front::spv::Options::default();
        assert!(naga::front::spv::parse_u8_slice(bytemuck::cast_slice(&late), &options).is_err());
    }

    #[test]
    fn contraction_allowed_is_naga_s_module_as_written() {
        let source = exp2_pass(crate::backend::schedule::pass_of("human_motion"));
        let allowed =
            compute_spirv(&source, "main", BufferBounds::Clamped, Contraction::Allowed).unwrap();
        let forbidden = compute_spirv(
            &source,
            "main",
            BufferBounds::Clamped,
            Contraction::Forbidden,
        )
        .unwrap();
        assert!(no_contraction_ids(&allowed).is_empty());
        assert_eq!(forbidden, without_contraction(&allowed));
    }

    #[test]
    fn a_bad_shader_is_an_error_saying_where_it_failed() {
        let e = compute_spirv(
            "fn main( {",
            "main",
            BufferBounds::Clamped,
            Contraction::Forbidden,
        )
        .unwrap_err();
        assert!(e.starts_with("WGSL parse"), "{e}");
        let e = compute_spirv(
            "@compute @workgroup_size(1) fn main() { let x: u32 = 1.5; }",
            "main",
            BufferBounds::Clamped,
            Contraction::Forbidden,
        )
        .unwrap_err();
        assert!(e.starts_with("WGSL"), "{e}");
    }

    /// Clamped, every storage-buffer index is clamped to the buffer's length (an `OpArrayLength`
    /// per runtime-sized buffer the code indexes, in the function that indexes it); left to the
    /// driver, none is, while the local array's index stays clamped either way.
    #[test]
    fn buffer_bounds_are_clamped_only_where_the_driver_does_not_check_them() {
        const OP_ARRAY_LENGTH: u32 = 68;
        let source = "
@group(0) @binding(0) var<storage, read_write> data: array<u32>;
fn bump(i: u32) { data[i] = data[i] + 1u; }
@compute @workgroup_size(1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    var local = array<u32, 4>(1u, 2u, 3u, 4u);
    bump(gid.x + local[gid.y]);
}
";
        let lengths = |buffers| {
            let words = compute_spirv(source, "main", buffers, Contraction::Allowed).unwrap();
            instructions(&words)
                .filter(|i| i.opcode == OP_ARRAY_LENGTH)
                .count()
        };
        assert!(lengths(BufferBounds::Clamped) > 0);
        assert_eq!(lengths(BufferBounds::Driver), 0);
        let clamped =
            compute_spirv(source, "main", BufferBounds::Clamped, Contraction::Allowed).unwrap();
        let driver =
            compute_spirv(source, "main", BufferBounds::Driver, Contraction::Allowed).unwrap();
        assert!(driver.len() < clamped.len());
    }
}
