//! Every `.wgsl` file under `shaders/` parses and validates with naga (no GPU needed): stage
//! shaders as the GPU backend assembles them (generated prelude included), libraries with their
//! requirements. The embedded copies are the files; the common libraries stay in step with their
//! Rust twins; the generated `StepParams` has the same layout in WGSL as in Rust; no shader
//! redefines a constant the generated heads take from Rust.
//!
//! Library files declare what they build on with header lines `// requires: <path>` (relative to
//! `shaders/`), before the first non-comment line. A file is validated with its requirements
//! prepended (recursively, each once, dependencies first), the way the stage shaders will be
//! assembled.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use socnav::backend::{schedule, wgsl};

fn shaders_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders")
}

fn wgsl_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            wgsl_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "wgsl") {
            out.push(p);
        }
    }
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The `// requires: <path>` lines of a file's leading comment block.
fn requires(src: &str) -> Vec<String> {
    src.lines()
        .map(str::trim)
        .take_while(|l| l.is_empty() || l.starts_with("//"))
        .filter_map(|l| l.strip_prefix("// requires:"))
        .map(|r| r.trim().to_owned())
        .collect()
}

/// Appends `path`'s requirements (recursively) and then `path` itself to `order`, each once.
fn resolve(path: &Path, order: &mut Vec<PathBuf>, visiting: &mut Vec<PathBuf>) {
    if order.iter().any(|p| p == path) {
        return;
    }
    assert!(
        !visiting.iter().any(|p| p == path),
        "require cycle through {}",
        path.display()
    );
    visiting.push(path.to_owned());
    for r in requires(&read(path)) {
        let dep = shaders_dir().join(&r);
        assert!(
            dep.is_file(),
            "{}: requires {r}, which does not exist",
            path.display()
        );
        resolve(&dep, order, visiting);
    }
    visiting.pop();
    order.push(path.to_owned());
}

/// Parses and validates `src` (named `label` in messages).
fn validate_source(src: &str, label: &str) -> Result<naga::Module, String> {
    validate_with_info(src, label).map(|(module, _)| module)
}

/// [`validate_source`], with what the validator found of each function (the globals each entry
/// point uses, say).
fn validate_with_info(
    src: &str,
    label: &str,
) -> Result<(naga::Module, naga::valid::ModuleInfo), String> {
    let module =
        naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string_with_path(src, label))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| e.emit_to_string_with_path(src, label))?;
    Ok((module, info))
}

/// Parses and validates `path` with its requirements prepended.
fn validate(path: &Path) -> Result<(), String> {
    let mut order = Vec::new();
    resolve(path, &mut order, &mut Vec::new());
    let src: String = order.iter().map(|p| read(p) + "\n").collect();
    let label = order
        .iter()
        .map(|p| {
            p.strip_prefix(shaders_dir())
                .unwrap_or(p)
                .display()
                .to_string()
        })
        .collect::<Vec<_>>()
        .join(" + ");
    validate_source(&src, &label).map(|_| ())
}

/// `shaders/<path>` as the GPU backend assembles it for a batch of experiment 2 (every column
/// kind in use): the generated prelude, the file's requirements, the file.
fn validate_assembled(path: &str) -> Result<naga::Module, String> {
    if wgsl::needs_sngnn(path) {
        return validate_assembled_sngnn(path);
    }
    let src = wgsl::assemble(path, &exp2_prelude())?;
    validate_source(&src, &format!("{path} (assembled)"))
}

/// The prelude of a batch of experiment 2 (every column kind in use).
fn exp2_prelude() -> String {
    let env = socnav::BatchEnv::new(
        socnav::Config::from_name_or_path("exp2").expect("exp2"),
        socnav::EnvOptions::default(),
    )
    .expect("batch");
    let columns = env.state().unwrap().columns();
    wgsl::prelude(
        &columns,
        &env.outputs().columns(),
        &wgsl::SizeClasses::of(&columns),
    )
}

/// Pass `pass` (`schedule::passes`) as the GPU backend assembles it for a batch of experiment 2,
/// with the SNGNN-v2 reward where the pass builds SNGNN graphs.
fn validate_pass(pass: &str) -> Result<naga::Module, String> {
    let sngnn = schedule::pass_files(pass)
        .iter()
        .any(|f| wgsl::needs_sngnn(f));
    let prelude = if sngnn {
        sngnn_prelude()
    } else {
        exp2_prelude()
    };
    let src = wgsl::assemble_pass(pass, &prelude)?;
    validate_source(&src, &format!("pass {pass} (assembled)"))
}

/// Each pass that resets from the pool (`schedule::reset_passes`) as the GPU backend
/// assembles it for a batch of experiment 2 whose pool rows leave their obstacles to the device
/// (`wgsl::assemble_pass_rebuilding_resets`), named `<pass>+rebuild`.
fn reset_rebuild_passes() -> Vec<(String, String)> {
    schedule::reset_passes()
        .into_iter()
        .map(|pass| {
            let src = wgsl::assemble_pass_rebuilding_resets(pass, &exp2_prelude())
                .unwrap_or_else(|e| panic!("{pass}: {e}"));
            (format!("{pass}+rebuild"), src)
        })
        .collect()
}

/// Every module the GPU backend compiles from `shaders/`, by name: each pass
/// (`schedule::passes`), each pass that resets as a batch assembles it whose rows leave their
/// obstacles to the device, then each network shader (standalone).
fn compiled_modules() -> Vec<(String, naga::Module)> {
    let mut out: Vec<(String, naga::Module)> = schedule::passes()
        .into_iter()
        .map(|p| {
            (
                p.to_owned(),
                validate_pass(p).unwrap_or_else(|e| panic!("{e}")),
            )
        })
        .collect();
    for (name, src) in reset_rebuild_passes() {
        let module = validate_source(&src, &name).unwrap_or_else(|e| panic!("{e}"));
        out.push((name, module));
    }
    for s in socnav::pipeline::STAGES {
        let file = s.shader_file();
        if wgsl::is_standalone(&file) {
            let src = wgsl::assemble_standalone(&file).expect("assembled");
            out.push((
                s.name.to_owned(),
                validate_source(&src, &file).expect("validates"),
            ));
        }
    }
    out
}

/// An SNGNN shader as `GpuStages::with_sngnn_graphs` assembles it for experiment 2 with the
/// SNGNN-v2 reward: the prelude of a state with the frame history (built without `BatchEnv`,
/// which would need the weights), then the SNGNN part.
fn validate_assembled_sngnn(path: &str) -> Result<naga::Module, String> {
    let src = wgsl::assemble(path, &sngnn_prelude())?;
    validate_source(&src, &format!("{path} (assembled, SNGNN)"))
}

/// The prelude of the SNGNN passes for experiment 2 with the SNGNN-v2 reward: the prelude of a
/// state with the frame history (built without `BatchEnv`, which would need the weights), then
/// the SNGNN part.
fn sngnn_prelude() -> String {
    let config = socnav::Config::from_name_or_path("exp2_sngnn").expect("exp2_sngnn");
    let caps = socnav::state::Caps::from_config(&config);
    let state = socnav::state::BatchState::new(4, caps);
    let layout = socnav::spec::ObsLayout::new(&caps, &config.observation);
    let outputs = socnav::outputs::Outputs::new(4, layout);
    let columns = state.columns();
    let mut prelude = wgsl::prelude(
        &columns,
        &outputs.columns(),
        &wgsl::SizeClasses::of(&columns),
    );
    prelude.push_str(&wgsl::sngnn_prelude());
    prelude
}

#[test]
fn all_wgsl_shaders_validate() {
    let mut files = Vec::new();
    wgsl_files(&shaders_dir(), &mut files);
    assert!(!files.is_empty(), "no .wgsl files under shaders/");
    let mut errors = Vec::new();
    for p in &files {
        let rel = p.strip_prefix(shaders_dir()).expect("under shaders/");
        let rel = rel.to_str().expect("UTF-8 path");
        // The library embeds what the backend compiles: it must be this very file.
        match wgsl::source(rel) {
            Some(embedded) if embedded == read(p) => {}
            Some(_) => errors.push(format!("{rel}: the embedded copy differs (rebuild)")),
            None => errors.push(format!("{rel} is not listed in backend::wgsl::FILES")),
        }
        if wgsl::is_standalone(rel) {
            // Its own bindings, no batch prelude: validated as the SNGNN host assembles it.
            let src = wgsl::assemble_standalone(rel).expect("assembled");
            errors.extend(validate_source(&src, rel).err());
            continue;
        }
        errors.extend(validate_assembled(rel).err());
        // The pure libraries also stand alone, with their requirements only.
        if matches!(rel, "common/math.wgsl" | "common/rng.wgsl") {
            errors.extend(validate(p).err());
        }
    }
    println!("validated {} shaders", files.len());
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// The top of `shaders/` is the step: one file per stage of `pipeline::STAGES` (named after it),
/// plus the reset pass (`schedule::RESET_PASS`), nothing else. A batch shader in a fused pass
/// (`schedule::fused_passes`) defines `stage_<name>` and no `main`, and its pass has `main`;
/// any other batch shader has the entry point `main`; a network shader assembles on its own
/// (`wgsl::is_standalone`). Each stage's file does what its GPU plan (`pipeline::GpuPlan`) says:
/// an entry point `queue_work` exactly where its rare work is queued, a regrouping
/// (`regroup_canonicalize`) exactly where it regroups, a reset from the pool
/// (`common/pool_reset.wgsl`) exactly where it resets.
#[test]
fn top_level_shaders_are_the_stages_and_the_reset_pass() {
    use socnav::pipeline::{STAGES, Shader};
    let mut expected: Vec<String> = STAGES.iter().map(|s| s.shader_file()).collect();
    expected.push(format!("{}.wgsl", schedule::RESET_PASS));
    expected.sort();
    let mut top: Vec<String> = wgsl::FILES
        .iter()
        .filter(|(p, _)| !p.contains('/'))
        .map(|(p, _)| (*p).to_owned())
        .collect();
    top.sort();
    assert_eq!(top, expected, "shaders/*.wgsl against the step's stages");
    for stage in &STAGES {
        let path = stage.shader_file();
        match stage.shader {
            Shader::Batch => {
                assert!(!wgsl::is_standalone(&path), "{path} has the batch prelude");
                let module = validate_assembled(&path).unwrap_or_else(|e| panic!("{e}"));
                let pass =
                    validate_pass(schedule::pass_of(stage.name)).unwrap_or_else(|e| panic!("{e}"));
                assert!(
                    pass.entry_points.iter().any(|ep| ep.name == "main"),
                    "the pass of shaders/{path} has no entry point `main`"
                );
                let file = wgsl::source(&path).expect("a stage shader");
                let queues = module
                    .entry_points
                    .iter()
                    .any(|ep| ep.name == schedule::QUEUE_ENTRY);
                assert_eq!(
                    queues,
                    stage.gpu.rare_work,
                    "shaders/{path}: `{}` against the plan's rare work",
                    schedule::QUEUE_ENTRY
                );
                let regroups = file.contains("regroup_canonicalize(");
                assert_eq!(
                    regroups, stage.gpu.regroups,
                    "shaders/{path}: regroupings against the plan"
                );
                let resets = file.contains("common/pool_reset.wgsl");
                assert_eq!(
                    resets, stage.gpu.resets,
                    "shaders/{path}: resets from the pool against the plan"
                );
                if schedule::fused_pass_of(stage.name).is_some() {
                    let function = format!("stage_{}", stage.name);
                    assert!(
                        module.entry_points.iter().all(|ep| ep.name != "main")
                            && module
                                .functions
                                .iter()
                                .any(|(_, f)| f.name.as_deref() == Some(function.as_str())),
                        "shaders/{path}, a member of a fused pass, defines `{function}` and no `main`"
                    );
                }
            }
            Shader::Network => {
                assert!(wgsl::is_standalone(&path), "{path} stands alone");
                let src = wgsl::assemble_standalone(&path).expect("assembled");
                validate_source(&src, &path).unwrap_or_else(|e| panic!("{e}"));
            }
        }
    }
}

/// The WGSL type of a struct member as a WGSL spelling (`f32`, `array<i32, 24>`), for the scalar
/// and array members `StepParams` may have; anything else is spelled with naga's debug form, so
/// that it differs from every Rust field's type.
fn naga_type_name(module: &naga::Module, ty: naga::Handle<naga::Type>) -> String {
    let scalar = |s: &naga::Scalar| match *s {
        naga::Scalar::F32 => Some("f32"),
        naga::Scalar::U32 => Some("u32"),
        naga::Scalar::I32 => Some("i32"),
        _ => None,
    };
    match &module.types[ty].inner {
        naga::TypeInner::Scalar(s) => scalar(s).map(str::to_owned),
        naga::TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            ..
        } => match &module.types[*base].inner {
            naga::TypeInner::Scalar(s) => scalar(s).map(|s| format!("array<{s}, {n}>")),
            _ => None,
        },
        _ => None,
    }
    .unwrap_or_else(|| format!("{:?}", module.types[ty].inner))
}

/// The generated `StepParams` (`wgsl::step_params_struct`, in every stage's prelude) has the
/// Rust struct's layout under WGSL's layout rules: as naga lays out an assembled stage shader,
/// every member has the Rust field's name, type, byte offset and size (`offset_of!` and
/// `size_of`, listed by `step_params!` in src/params.rs), and the struct has Rust's size.
/// Generation makes the names and their order agree; what can still differ is the layout: a
/// member whose WGSL alignment, array stride or padding is not repr(C)'s (a vector, a uniform
/// array with its 16-byte stride, a struct size rounded up), or a Rust field the list lacks.
#[test]
fn generated_step_params_layout_matches_rust() {
    use socnav::StepParams;
    let module = validate_assembled("reward.wgsl").unwrap_or_else(|e| panic!("{e}"));
    let layouter = {
        let mut l = naga::proc::Layouter::default();
        l.update(module.to_ctx()).expect("layout");
        l
    };
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("StepParams"))
        .expect("struct StepParams in the prelude");
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("StepParams is not a struct")
    };
    let size = std::mem::size_of::<StepParams>();
    assert_eq!(*span as usize, size, "size of StepParams (WGSL vs Rust)");
    assert_eq!(layouter[handle].size as usize, size);
    // The field list covers the Rust struct: its fields tile it, in order, without gaps.
    let mut end = 0;
    for f in StepParams::WGSL_FIELDS {
        assert_eq!(
            f.offset, end,
            "StepParams::{} follows its predecessor",
            f.name
        );
        end += f.size;
    }
    assert_eq!(end, size, "StepParams::WGSL_FIELDS covers the struct");
    let wgsl: Vec<(String, String, usize, usize)> = members
        .iter()
        .map(|m| {
            (
                m.name.clone().unwrap_or_default(),
                naga_type_name(&module, m.ty),
                m.offset as usize,
                layouter[m.ty].size as usize,
            )
        })
        .collect();
    let rust: Vec<(String, String, usize, usize)> = StepParams::WGSL_FIELDS
        .iter()
        .map(|f| (f.wgsl_name().to_owned(), f.wgsl_type(), f.offset, f.size))
        .collect();
    assert_eq!(wgsl.len(), rust.len(), "StepParams member count");
    for (w, r) in wgsl.iter().zip(&rust) {
        assert_eq!(
            w, r,
            "StepParams member (name, type, offset, size): WGSL vs Rust"
        );
    }
}

/// The names of the `const` declarations (module or function scope) in WGSL source `src`, one
/// per line that starts with `const` (comment lines do not).
fn wgsl_const_names(src: &str) -> BTreeSet<String> {
    src.lines()
        .filter_map(|l| l.trim().strip_prefix("const "))
        .map(|rest| {
            rest.trim_start()
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect()
        })
        .collect()
}

/// A constant is written once: no file under shaders/ declares a constant that a generated head
/// already defines from its Rust value (the stages' prelude, the SNGNN passes' part of it, the
/// standalone shaders' head). Naga rejects such a pair only where both meet in one assembled
/// shader; this catches it in any file.
#[test]
fn shaders_do_not_redefine_generated_constants() {
    let generated: BTreeSet<String> = [sngnn_prelude(), wgsl::standalone_head()]
        .iter()
        .flat_map(|head| wgsl_const_names(head))
        .collect();
    for name in [
        "WORKGROUP_SIZE",
        "REWARD_SNGNN",
        "SNGNN_WEIGHT",
        "CONTACT_SLOP",
        "GEO_POLY64_COS",
        "SN_FRAME_PERIOD",
        "STATUS_EMPTY",
    ] {
        assert!(generated.contains(name), "the generated heads lack {name}");
    }
    let mut files = Vec::new();
    wgsl_files(&shaders_dir(), &mut files);
    let mut twice = Vec::new();
    for p in &files {
        let rel = p.strip_prefix(shaders_dir()).expect("under shaders/");
        for name in wgsl_const_names(&read(p)).intersection(&generated) {
            twice.push(format!("shaders/{}: {name}", rel.display()));
        }
    }
    assert!(
        twice.is_empty(),
        "constants the generated heads define from Rust, declared again in a shader: {twice:?}"
    );
}

/// The 32-bit pattern of every hexadecimal literal in `src`: integers as written (without `_`
/// separators or WGSL suffixes), and WGSL hexadecimal floats (`-0x1.921fb6p1f`) as the bits of
/// the f32 they denote. Rust gives float constants as `f32::from_bits(0x...)`, WGSL as exact
/// hexadecimal floats (naga cannot evaluate `bitcast` in a constant expression), so both sides
/// reduce to the same patterns.
fn hex_literals(src: &str) -> BTreeSet<u32> {
    let b = src.as_bytes();
    let mut out = BTreeSet::new();
    let mut i = 0;
    while i + 1 < b.len() {
        let starts_token = i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        if !(starts_token && b[i] == b'0' && (b[i + 1] == b'x' || b[i + 1] == b'X')) {
            i += 1;
            continue;
        }
        let negative = i > 0 && b[i - 1] == b'-';
        let mut j = i + 2;
        let take_hex = |j: &mut usize| {
            let mut digits = String::new();
            while *j < b.len() && (b[*j].is_ascii_hexdigit() || b[*j] == b'_') {
                if b[*j] != b'_' {
                    digits.push(b[*j] as char);
                }
                *j += 1;
            }
            digits
        };
        let int_digits = take_hex(&mut j);
        let is_float = j < b.len() && (b[j] == b'.' || b[j] == b'p' || b[j] == b'P');
        if !is_float {
            if !int_digits.is_empty() {
                let v = u64::from_str_radix(&int_digits, 16).expect("hex digits");
                out.insert(u32::try_from(v).expect("hex literal wider than 32 bits"));
            }
            i = j;
            continue;
        }
        let mut frac_digits = String::new();
        if b[j] == b'.' {
            j += 1;
            frac_digits = take_hex(&mut j);
        }
        assert!(b[j] == b'p' || b[j] == b'P', "hex float without exponent");
        j += 1;
        let exp_start = j;
        while j < b.len() && (b[j] == b'-' || b[j] == b'+' || b[j].is_ascii_digit()) {
            j += 1;
        }
        let exp: i32 = src[exp_start..j].parse().expect("hex float exponent");
        // Mantissa as an integer, scaled by 2^(exp - 4·fraction digits): exact in f64 for the
        // 24-bit mantissas of f32 constants, then exact again in f32.
        let mantissa = u64::from_str_radix(&format!("{int_digits}{frac_digits}"), 16)
            .expect("hex float digits");
        let value = mantissa as f64 * 2f64.powi(exp - 4 * frac_digits.len() as i32);
        let value = if negative { -value } else { value };
        let f = value as f32;
        assert_eq!(f64::from(f), value, "inexact hex float in WGSL");
        out.insert(f.to_bits());
        i = j;
    }
    out
}

fn repo_file(rel: &str) -> String {
    read(&Path::new(env!("CARGO_MANIFEST_DIR")).join(rel))
}

/// A constant changed on one side only (a coefficient, a mask, a mixer multiplier) shows up as a
/// literal that the other side lacks.
#[test]
fn wgsl_twins_use_the_same_hex_constants() {
    for (rust, wgsl) in [
        ("src/math.rs", "shaders/common/math.wgsl"),
        ("src/rng.rs", "shaders/common/rng.wgsl"),
    ] {
        let r = hex_literals(&repo_file(rust));
        let w = hex_literals(&repo_file(wgsl));
        assert!(r.len() >= 4, "{rust}: only {} hex literals found", r.len());
        let hex =
            |set: BTreeSet<&u32>| set.iter().map(|v| format!("{v:#010x}")).collect::<Vec<_>>();
        let only_rust = hex(r.difference(&w).collect());
        let only_wgsl = hex(w.difference(&r).collect());
        assert!(
            only_rust.is_empty() && only_wgsl.is_empty(),
            "{rust} vs {wgsl}: only in Rust {only_rust:?}, only in WGSL {only_wgsl:?}"
        );
    }
}

/// The 64-gon constants that the shaders' head gets from src/geometry.rs
/// (`wgsl::geometry_constants`) denote the Rust bits, table entries in order.
#[test]
fn generated_geometry_constants_denote_the_rust_bits() {
    use socnav::geometry::{POLY64_COS, POLY64_INNER, POLY64_OUTER};
    let head = wgsl::geometry_constants();
    let bits = |literal: &str| -> u32 {
        let set = hex_literals(literal.trim());
        match set.len() {
            0 if ["0.0f", "-0.0f"].contains(&literal.trim()) => {
                if literal.trim().starts_with('-') {
                    0x8000_0000
                } else {
                    0
                }
            }
            1 => *set.first().expect("one"),
            _ => panic!("not one literal: {literal}"),
        }
    };
    let value_of = |name: &str| -> &str {
        let start = head.find(&format!("const {name}")).expect(name);
        let line = head[start..].lines().next().expect("a line");
        line.split('=')
            .nth(1)
            .expect("a value")
            .trim_end_matches(';')
    };
    assert_eq!(
        bits(value_of("GEO_POLY64_OUTER: f32")),
        POLY64_OUTER.to_bits()
    );
    assert_eq!(
        bits(value_of("GEO_POLY64_INNER: f32")),
        POLY64_INNER.to_bits()
    );
    let table = value_of("GEO_POLY64_COS");
    let inner = table
        .trim()
        .strip_prefix("array<f32, 64>(")
        .and_then(|t| t.strip_suffix(')'))
        .expect("array<f32, 64>(...)");
    let got: Vec<u32> = inner.split(',').map(bits).collect();
    let want: Vec<u32> = POLY64_COS.iter().map(|v| v.to_bits()).collect();
    assert_eq!(got, want);
}

/// Names of `pub fn` and `pub const` items in a Rust source (top level and impl blocks).
fn rust_pub_items(src: &str, keyword: &str) -> BTreeSet<String> {
    src.lines()
        .filter_map(|l| l.trim().strip_prefix(keyword))
        .map(|rest| {
            rest.chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect()
        })
        .collect()
}

/// Every public function and constant of the Rust twins exists in WGSL under its prefixed name.
#[test]
fn wgsl_twins_define_every_public_item() {
    let math_wgsl = repo_file("shaders/common/math.wgsl");
    let math_rs = repo_file("src/math.rs");
    for f in rust_pub_items(&math_rs, "pub fn ") {
        assert!(
            math_wgsl.contains(&format!("fn math_{f}(")),
            "math.wgsl lacks math_{f}"
        );
    }
    for c in rust_pub_items(&math_rs, "pub const ") {
        assert!(
            math_wgsl.contains(&format!("const MATH_{c}:")),
            "math.wgsl lacks MATH_{c}"
        );
    }
    let rng_wgsl = repo_file("shaders/common/rng.wgsl");
    for f in rust_pub_items(&repo_file("src/rng.rs"), "pub fn ") {
        // `new` takes the u64 seed, which WGSL cannot hold: its twin is `from_seed_words`.
        let twin = match f.as_str() {
            "new" | "from_seed_words" => "new".to_owned(),
            other => other.to_owned(),
        };
        assert!(
            rng_wgsl.contains(&format!("fn rng_{twin}(")),
            "rng.wgsl lacks rng_{twin} (twin of {f})"
        );
    }
}

/// The preludes are the only config-dependent shader text, and the size classes put every
/// shipped config into one prelude (`stress`'s 304 obstacle vertices included: ORCA's obstacle
/// processing works in the `scratch` buffer, not in arrays sized by a capacity), so that a
/// process (or CI) that runs them all compiles each stage shader once, not once per config (or
/// batch size).
#[test]
fn shipped_configs_share_one_prelude() {
    let mut preludes = std::collections::BTreeMap::<String, Vec<String>>::new();
    for (name, state, outputs) in shipped_tables() {
        let columns = state.columns();
        let classes = wgsl::SizeClasses::of(&columns);
        let prelude = wgsl::prelude(&columns, &outputs.columns(), &classes);
        preludes.entry(prelude).or_default().push(name.to_owned());
    }
    let groups: Vec<Vec<String>> = preludes.into_values().collect();
    assert_eq!(groups.len(), 1, "configs by prelude: {groups:?}");
}

/// Every shipped config's name with a one-environment state and outputs (what its shaders'
/// generated text is made from).
fn shipped_tables() -> Vec<(
    &'static str,
    socnav::state::BatchState,
    socnav::outputs::Outputs,
)> {
    socnav::Config::shipped_names()
        .map(|name| {
            let config = socnav::Config::from_name_or_path(name).expect("a shipped config");
            let caps = socnav::state::Caps::from_config(&config);
            let layout = socnav::spec::ObsLayout::new(&caps, &config.observation);
            (
                name,
                socnav::state::BatchState::new(1, caps),
                socnav::outputs::Outputs::new(1, layout),
            )
        })
        .collect()
}

/// One environment's working memory for ORCA's obstacles, by hand for `stress`'s 304 vertices:
/// a list of 38 polygons (2 + 38 * 8 words), a set of 304 vertices (2 + 7 * 304) and a stack of
/// 3 * 304; and at least a word of each with no obstacle capacity at all.
#[test]
fn obstacle_scratch_layout() {
    let columns = [("ov_x", socnav::state::columns::Elem::F32, 304)];
    let s = wgsl::ObstacleScratch::of(&columns);
    assert_eq!((s.list, s.set, s.stack), (0, 306, 306 + 2 + 2128));
    assert_eq!(s.words, 2436 + 912);
    let none = wgsl::ObstacleScratch::of(&[]);
    assert_eq!(
        (none.list, none.set, none.stack, none.words),
        (0, 10, 19, 22)
    );
}

/// An environment's region of `scratch` holds the obstacle processing's working memory and the
/// slot permutations' old slots (every permuted kind's at once: a word per column and slot of
/// each), by hand: 2 human columns of 16 slots and a group column of 3 (35 words) outgrow the
/// obstacles of 1 vertex (22 words); 8 vertices (92 words) outgrow them; and for every shipped
/// config.
#[test]
fn scratch_region_holds_obstacles_and_permutations() {
    use socnav::state::columns::Elem;
    let humans = [
        ("h_x", Elem::F32, 16),
        ("h_role", Elem::U32, 16),
        ("g_first", Elem::U32, 3),
    ];
    let with = |vertices: usize| {
        let mut columns = humans.to_vec();
        columns.push(("ov_x", Elem::F32, vertices));
        wgsl::scratch_region_words(&columns)
    };
    assert_eq!(with(1), 35);
    assert_eq!(with(8), 92);
    // Every shipped config: the region holds every permuted kind's columns times its capacity,
    // all at once, and the obstacle words.
    for (name, state, _) in shipped_tables() {
        let columns = state.columns();
        let region = wgsl::scratch_region_words(&columns);
        let mut permuted = 0;
        for kind in ["human", "group", "laptop_user", "laptop"] {
            let of_kind: Vec<_> = columns
                .iter()
                .filter(|c| {
                    socnav::state::BatchState::COLUMN_KINDS
                        .iter()
                        .any(|&(col, k)| col == c.0 && k == kind)
                })
                .collect();
            let words = of_kind.len() * of_kind.iter().map(|c| c.2).max().unwrap_or(0);
            assert!(kind != "human" || words > 0, "{name}: no human slots");
            permuted += words;
        }
        assert!(
            region >= permuted,
            "{name}: {region} words < {permuted} of permuted slots"
        );
        assert!(
            region >= wgsl::ObstacleScratch::of(&columns).words,
            "{name}"
        );
    }
}

/// The GPU backend's pool scatter pass (`wgsl::pool_scatter_shader`) validates, and reads a run
/// as `wgsl::POOL_RUN_WORDS` words in a workgroup of `wgsl::WORKGROUP_SIZE` lanes.
#[test]
fn the_pool_scatter_pass_validates() {
    validate_source(&wgsl::pool_scatter_shader(true), "pool scatter, last first")
        .expect("validates");
    let src = wgsl::pool_scatter_shader(false);
    validate_source(&src, "pool scatter").expect("validates");
    assert!(src.contains(&format!(
        "const RUN_WORDS: u32 = {}u;",
        wgsl::POOL_RUN_WORDS
    )));
    assert!(src.contains(&format!(
        "const WORKGROUP_SIZE: u32 = {}u;",
        wgsl::WORKGROUP_SIZE
    )));
}

/// The GPU backend's finished-rows pass (`wgsl::finished_rows_shader`, generated from the output
/// columns) validates for every shipped config and is the same text for all of them (one
/// pipeline per device); its row is the environment's index and the finished-only columns.
#[test]
fn the_finished_rows_pass_validates_and_is_shared() {
    let mut sources = BTreeSet::new();
    for (name, state, outputs) in shipped_tables() {
        let src = wgsl::finished_rows_shader(&state.columns(), &outputs.columns());
        validate_source(&src, &format!("finished rows ({name})")).expect("validates");
        let row: usize = outputs
            .columns()
            .iter()
            .filter(|c| socnav::outputs::FINISHED_ONLY_COLUMNS.contains(&c.0))
            .map(|c| c.2)
            .sum();
        assert_eq!(
            wgsl::finished_row_words(&outputs.columns()),
            1 + row,
            "{name}"
        );
        assert_eq!(
            wgsl::finished_columns(&outputs.columns()).len(),
            socnav::outputs::FINISHED_ONLY_COLUMNS.len(),
            "every finished-only column is an output column"
        );
        sources.insert(src);
    }
    assert_eq!(
        sources.len(),
        1,
        "the finished-rows pass differs between configs"
    );
}

/// Bytes of function-scope arrays in `module`, per function: naga's SPIR-V writer gives every
/// function-local variable without an initialiser a zero one (`OpConstantNull`), so each call of
/// the function zeroes them whether it reads them or not (issue 19).
fn zeroed_local_array_bytes(module: &naga::Module) -> Vec<(String, u32)> {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    let functions = module
        .functions
        .iter()
        .map(|(_, f)| f)
        .chain(module.entry_points.iter().map(|e| &e.function));
    functions
        .map(|f| {
            let bytes = f
                .local_variables
                .iter()
                .filter(|(_, v)| v.init.is_none() && holds_array(module, v.ty))
                .map(|(_, v)| layouter[v.ty].size)
                .sum();
            (f.name.clone().unwrap_or_default(), bytes)
        })
        .filter(|&(_, b)| b > 0)
        .collect()
}

/// Whether type `ty` is an array or a struct holding one (at any depth).
fn holds_array(module: &naga::Module, ty: naga::Handle<naga::Type>) -> bool {
    match &module.types[ty].inner {
        naga::TypeInner::Array { .. } => true,
        naga::TypeInner::Struct { members, .. } => {
            members.iter().any(|m| holds_array(module, m.ty))
        }
        _ => false,
    }
}

/// A ratchet on the zero-initialised function-scope arrays of every stage shader (as assembled for
/// exp2): no function may zero more bytes per call than it does today, so a change that adds one
/// fails here and one that removes one lowers the table. The largest are ORCA's fixed-size lists
/// (`orca_world_velocity`: the agent and obstacle neighbours and the lines, 4,640 bytes a call;
/// LP3's projected lines, 3,088 bytes, only in the calls that need LP3), sized by limits that
/// every shipped config shares so that each stage shader compiles once (issue 14).
#[test]
fn zeroed_function_scope_arrays_do_not_grow() {
    // Pass::function, bytes zeroed per call (exp2's assembly; `schedule::passes`).
    const BUDGET: &[(&str, u32)] = &[
        ("motion::state_permute_humans", 512),
        ("motion::state_permute_groups", 512),
        ("motion::state_permute_laptop_users", 256),
        ("motion::state_permute_laptops", 512),
        ("motion::orca_lp3", 3088),
        ("motion::orca_obstacles_corners", 32),
        ("motion::orca_obstacles_polygon", 72),
        ("motion::orca_world_velocity", 4640),
        ("crowd::state_permute_humans", 512),
        ("crowd::state_permute_groups", 512),
        ("crowd::state_permute_laptop_users", 256),
        ("crowd::state_permute_laptops", 512),
        ("crowd::orca_lp3", 3088),
        ("crowd::orca_obstacles_corners", 32),
        ("crowd::orca_obstacles_polygon", 72),
        ("crowd::orca_world_velocity", 4640),
        ("outcome::state_permute_humans", 512),
        ("outcome::state_permute_groups", 512),
        ("outcome::state_permute_laptop_users", 256),
        ("outcome::state_permute_laptops", 512),
        ("outcome::obs_noise", 20),
        ("begin_step::state_permute_humans", 512),
        ("begin_step::state_permute_groups", 512),
        ("begin_step::state_permute_laptop_users", 256),
        ("begin_step::state_permute_laptops", 512),
        ("formation::state_permute_humans", 512),
        ("formation::state_permute_groups", 512),
        ("formation::state_permute_laptop_users", 256),
        ("formation::state_permute_laptops", 512),
        ("formation::orca_lp3", 3088),
        ("formation::orca_obstacles_corners", 32),
        ("formation::orca_obstacles_polygon", 72),
        ("formation::regroup_sorted", 1284),
        ("formation::regroup_inverse", 256),
        ("formation::regroup_remap", 1024),
        ("formation::regroup_canonicalize", 1040),
        ("formation::form_crowd", 128),
        ("formation::form_approximate_crowd", 128),
        ("sngnn_graph::state_permute_humans", 512),
        ("sngnn_graph::state_permute_groups", 512),
        ("sngnn_graph::state_permute_laptop_users", 256),
        ("sngnn_graph::state_permute_laptops", 512),
        ("sngnn_graph::sn_select", 16),
        ("social_events::state_permute_humans", 512),
        ("social_events::state_permute_groups", 512),
        ("social_events::state_permute_laptop_users", 256),
        ("social_events::state_permute_laptops", 512),
        ("social_events::orca_lp3", 3088),
        ("social_events::orca_obstacles_corners", 32),
        ("social_events::orca_obstacles_polygon", 72),
        ("social_events::regroup_sorted", 1284),
        ("social_events::regroup_inverse", 256),
        ("social_events::regroup_remap", 1024),
        ("social_events::regroup_canonicalize", 1040),
        ("social_events::crowd_dispersal", 268),
        ("social_events::laptop_dispersal", 260),
        ("social_events::crowd_formation", 420),
        ("social_events::laptop_formation", 520),
        ("autoreset::state_permute_humans", 512),
        ("autoreset::state_permute_groups", 512),
        ("autoreset::state_permute_laptop_users", 256),
        ("autoreset::state_permute_laptops", 512),
        ("reset::state_permute_humans", 512),
        ("reset::state_permute_groups", 512),
        ("reset::state_permute_laptop_users", 256),
        ("reset::state_permute_laptops", 512),
        ("begin_step+rebuild::orca_lp3", 3088),
        ("begin_step+rebuild::orca_obstacles_corners", 32),
        ("begin_step+rebuild::orca_obstacles_polygon", 72),
        ("autoreset+rebuild::orca_lp3", 3088),
        ("autoreset+rebuild::orca_obstacles_corners", 32),
        ("autoreset+rebuild::orca_obstacles_polygon", 72),
        ("reset+rebuild::orca_lp3", 3088),
        ("reset+rebuild::orca_obstacles_corners", 32),
        ("reset+rebuild::orca_obstacles_polygon", 72),
    ];
    let mut report = Vec::new();
    let mut over = Vec::new();
    for (pass, module) in compiled_modules() {
        for (function, bytes) in zeroed_local_array_bytes(&module) {
            let key = format!("{pass}::{function}");
            let budget = BUDGET.iter().find(|(k, _)| *k == key).map_or(0, |b| b.1);
            if bytes > budget {
                over.push(format!("{key}: {bytes} bytes (budget {budget})"));
            }
            report.push(format!("(\"{key}\", {bytes}),"));
        }
    }
    // The table's current values, to paste after a change lowers them.
    println!("{}", report.join("\n"));
    assert!(
        over.is_empty(),
        "zeroed function-scope arrays grew:\n{}",
        over.join("\n")
    );
}

/// Zero-initialised function-scope arrays (or structs holding one) of `module` that their
/// function never reads, as `function: variable`. naga's SPIR-V writer zeroes every local
/// variable without an initialiser on each call, so such an array is pure cost. A variable is
/// read when a `Load` goes through it (or a part of it), or when it is passed by pointer to a
/// function that reads that parameter (followed through calls to a fixed point).
fn unread_zeroed_local_arrays(module: &naga::Module) -> Vec<String> {
    use naga::{Expression, Function, Handle, Statement};
    // The local variable or parameter a pointer expression is a part of.
    #[derive(Clone, Copy, PartialEq)]
    enum Root {
        Local(Handle<naga::LocalVariable>),
        Argument(u32),
    }
    fn root(f: &Function, mut e: Handle<Expression>) -> Option<Root> {
        loop {
            match f.expressions[e] {
                Expression::Access { base, .. } | Expression::AccessIndex { base, .. } => e = base,
                Expression::LocalVariable(v) => return Some(Root::Local(v)),
                Expression::FunctionArgument(i) => return Some(Root::Argument(i)),
                _ => return None,
            }
        }
    }
    // Every call in a block, at any depth: (callee, arguments).
    fn calls(block: &naga::Block, out: &mut Vec<(Handle<Function>, Vec<Handle<Expression>>)>) {
        for statement in block.iter() {
            match statement {
                Statement::Call {
                    function,
                    arguments,
                    ..
                } => out.push((*function, arguments.clone())),
                Statement::Block(b) => calls(b, out),
                Statement::If { accept, reject, .. } => {
                    calls(accept, out);
                    calls(reject, out);
                }
                Statement::Switch { cases, .. } => cases.iter().for_each(|c| calls(&c.body, out)),
                Statement::Loop {
                    body, continuing, ..
                } => {
                    calls(body, out);
                    calls(continuing, out);
                }
                _ => {}
            }
        }
    }
    // The roots `f` reads: through its own loads, and through the parameters of its callees
    // that `reads_parameter` says are read.
    let reads = |f: &Function, reads_parameter: &dyn Fn(Handle<Function>, usize) -> bool| {
        let mut read: Vec<Root> = f
            .expressions
            .iter()
            .filter_map(|(_, e)| match *e {
                Expression::Load { pointer } => root(f, pointer),
                _ => None,
            })
            .collect();
        let mut call_list = Vec::new();
        calls(&f.body, &mut call_list);
        for (callee, arguments) in call_list {
            for (i, &a) in arguments.iter().enumerate() {
                if let Some(r) = root(f, a).filter(|_| reads_parameter(callee, i)) {
                    read.push(r);
                }
            }
        }
        read
    };
    // Which parameters each function reads, to a fixed point (calls may nest).
    let handles: Vec<Handle<Function>> = module.functions.iter().map(|(h, _)| h).collect();
    let mut read_params: std::collections::HashSet<(Handle<Function>, usize)> = Default::default();
    loop {
        let before = read_params.len();
        for &h in &handles {
            let known = read_params.clone();
            for r in reads(&module.functions[h], &|c, i| known.contains(&(c, i))) {
                if let Root::Argument(i) = r {
                    read_params.insert((h, i as usize));
                }
            }
        }
        if read_params.len() == before {
            break;
        }
    }
    let functions = module
        .functions
        .iter()
        .map(|(_, f)| f)
        .chain(module.entry_points.iter().map(|e| &e.function));
    let mut unread = Vec::new();
    for f in functions {
        let read = reads(f, &|c, i| read_params.contains(&(c, i)));
        for (v, var) in f.local_variables.iter() {
            if var.init.is_none() && holds_array(module, var.ty) && !read.contains(&Root::Local(v))
            {
                let name = var.name.clone().unwrap_or_default();
                unread.push(format!("{}: {name}", f.name.clone().unwrap_or_default()));
            }
        }
    }
    unread
}

/// Issue 19: no shader zeroes a function-scope array that its function does not read. (ORCA's
/// LP3 working memory, once declared by every ORCA call and read only when LP2 fails, is
/// `orca_lp3`'s own.)
#[test]
fn every_zeroed_function_scope_array_is_read() {
    let mut unread = Vec::new();
    for (name, module) in compiled_modules() {
        unread.extend(
            unread_zeroed_local_arrays(&module)
                .into_iter()
                .map(|u| format!("{name}::{u}")),
        );
    }
    assert!(unread.is_empty(), "zeroed and never read: {unread:?}");
}

/// The check above finds an array that is zeroed and never read, one only written, and one
/// passed to a function that only writes it; it passes one read directly or through a callee.
#[test]
fn the_unread_array_check_finds_unread_arrays() {
    let src = r"
fn fill(a: ptr<function, array<u32, 4>>) { (*a)[0] = 1u; }
fn first(a: ptr<function, array<u32, 4>>) -> u32 { return (*a)[0]; }
fn pass_on(a: ptr<function, array<u32, 4>>) -> u32 { return first(a); }
@group(0) @binding(0) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(1)
fn main() {
    var never: array<u32, 4>;
    var written: array<u32, 4>;
    written[1] = 2u;
    var filled: array<u32, 4>;
    fill(&filled);
    var loaded: array<u32, 4>;
    var through: array<u32, 4>;
    fill(&through);
    out[0] = loaded[2] + pass_on(&through);
}
";
    let module = naga::front::wgsl::parse_str(src).expect("parses");
    assert_eq!(
        unread_zeroed_local_arrays(&module),
        ["main: never", "main: written", "main: filled"]
    );
}

/// The passes of the stages whose rare work runs out of the hot pass (`schedule::has_rare_work`)
/// have the entry point that queues their environments besides `main`, the pass of the
/// observation has the one that writes its entity records a lane each (`wgsl::OBS_RECORDS_ENTRY`)
/// and the one that moves its staged values into rows (`wgsl::OBS_ROWS_ENTRY`), the
/// passes that regroup the two that rebuild ORCA obstacles (`schedule::regroups`), as do the
/// passes that reset where the pool's rows leave their obstacles to the device
/// (`schedule::rebuilds_resets`), and no other pass has another; only those reset.
#[test]
fn passes_have_their_second_entry_points() {
    let passes = schedule::passes()
        .into_iter()
        .map(|p| (p.to_owned(), validate_pass(p).expect("validates")));
    let resets = reset_rebuild_passes().into_iter().map(|(name, src)| {
        (
            name.clone(),
            validate_source(&src, &name).expect("validates"),
        )
    });
    for (name, module) in passes.chain(resets) {
        let pass = name.trim_end_matches("+rebuild");
        let mut entries: Vec<&str> = module
            .entry_points
            .iter()
            .map(|e| e.name.as_str())
            .collect();
        entries.sort_unstable();
        let mut expected = vec!["main"];
        if schedule::has_rare_work(pass) {
            expected.push(schedule::QUEUE_ENTRY);
        }
        if pass == schedule::pass_of(wgsl::OBS_ROWS_STAGE) {
            expected.extend([wgsl::OBS_RECORDS_ENTRY, wgsl::OBS_ROWS_ENTRY]);
        }
        if schedule::regroups(pass) || name.ends_with("+rebuild") {
            expected.extend([wgsl::REBUILD_ENTRY, wgsl::REBUILD_IN_WORKGROUPS_ENTRY]);
        }
        expected.sort_unstable();
        assert_eq!(entries, expected, "{name}");
    }
    assert!(wgsl::assemble_pass_rebuilding_resets("formation", &exp2_prelude()).is_err());
}

/// The passes that regroup (`schedule::regroups`) validate with their environments taken a
/// workgroup each (`wgsl::with_regroups_in_workgroups`, the hardware adapters' way: every barrier
/// of the regrouping on lanes in uniform control flow), and their `main` then uses the
/// regrouping's workgroup variables, `wgsl::regroup_workgroup_bytes` of them (what the GPU
/// backend checks against the device's limit).
#[test]
fn regroup_passes_validate_with_their_regroupings_on_lanes() {
    let env = socnav::BatchEnv::new(
        socnav::Config::from_name_or_path("exp2").expect("exp2"),
        socnav::EnvOptions::default(),
    )
    .expect("batch");
    let classes = wgsl::SizeClasses::of(&env.state().unwrap().columns());
    let prelude = exp2_prelude();
    let lanes = wgsl::with_regroups_in_workgroups(&prelude);
    assert_ne!(
        lanes, prelude,
        "the prelude says how many lanes a regrouping takes"
    );
    for pass in schedule::passes()
        .into_iter()
        .filter(|p| schedule::regroups(p))
    {
        let src = wgsl::assemble_pass(pass, &lanes).expect("assembled");
        let (module, info) = validate_with_info(&src, &format!("pass {pass} (regroupings)"))
            .unwrap_or_else(|e| panic!("{e}"));
        let main = module
            .entry_points
            .iter()
            .position(|e| e.name == "main")
            .expect("main");
        let uses = info.get_entry_point(main);
        let bytes: u32 = module
            .global_variables
            .iter()
            .filter(|&(h, v)| {
                v.space == naga::AddressSpace::WorkGroup
                    && v.name
                        .as_deref()
                        .is_some_and(|n| n.starts_with("regroup_wg_"))
                    && !uses[h].is_empty()
            })
            .map(|(_, v)| module.types[v.ty].inner.size(module.to_ctx()))
            .sum();
        assert_eq!(
            bytes as usize,
            wgsl::regroup_workgroup_bytes(&classes),
            "{pass}: the regrouping's workgroup memory"
        );
    }
}

/// The passes that rebuild ORCA obstacles (`schedule::regroups`) validate with the obstacle
/// library's working memory in a workgroup array (`wgsl::with_obstacles_in_workgroup`), as the
/// GPU backend builds their `wgsl::REBUILD_IN_WORKGROUPS_ENTRY` on hardware adapters: no access
/// to `scratch` left, one workgroup variable of `OBSTACLES_IN_WORKGROUP_WORDS` words, which every
/// shipped config's obstacle region fits, and with the lanes' shared words
/// `REBUILD_WORKGROUP_WORDS` in all that the entry point uses (16 KiB, which every WebGPU adapter
/// has; the module's other entry points have workgroup variables of their own); no pass but those
/// regroups, and none of their `main`s rebuilds (the rebuild entry points do, after it). The same
/// for the passes that reset, as a batch whose pool rows leave their obstacles to the device
/// assembles them.
#[test]
fn rebuild_passes_keep_their_obstacles_in_workgroup_memory() {
    let passes = schedule::passes().into_iter().map(|pass| {
        let src = wgsl::assemble_pass(pass, &exp2_prelude()).expect("assembled");
        (pass.to_owned(), src, schedule::regroups(pass))
    });
    let resets = reset_rebuild_passes()
        .into_iter()
        .map(|(n, s)| (n, s, true));
    for (pass, src, rebuilds) in passes.chain(resets) {
        if !rebuilds {
            assert!(
                !src.contains("regroup_canonicalize("),
                "{pass}: a pass that regroups without rebuilding after it"
            );
            continue;
        }
        let moved = wgsl::with_obstacles_in_workgroup(&src)
            .unwrap_or_else(|| panic!("{pass}: no obstacle library"));
        assert!(!moved.contains("scratch["), "{pass}: scratch still read");
        let (module, info) =
            validate_with_info(&moved, &format!("pass {pass} (obstacles in workgroup)"))
                .unwrap_or_else(|e| panic!("{e}"));
        let entry = module
            .entry_points
            .iter()
            .position(|e| e.name == wgsl::REBUILD_IN_WORKGROUPS_ENTRY)
            .unwrap_or_else(|| panic!("{pass}: no {}", wgsl::REBUILD_IN_WORKGROUPS_ENTRY));
        let uses = info.get_entry_point(entry);
        let workgroup: Vec<(u32, u32)> = module
            .global_variables
            .iter()
            .filter(|&(h, v)| v.space == naga::AddressSpace::WorkGroup && !uses[h].is_empty())
            .map(|(_, v)| {
                let inner = &module.types[v.ty].inner;
                let len = match *inner {
                    naga::TypeInner::Array {
                        size: naga::ArraySize::Constant(n),
                        base,
                        ..
                    } if module.types[base].inner == naga::TypeInner::Scalar(naga::Scalar::U32) => {
                        n.get()
                    }
                    _ => 0,
                };
                (len, inner.size(module.to_ctx()))
            })
            .collect();
        let regions = workgroup
            .iter()
            .filter(|&&(len, _)| len == wgsl::OBSTACLES_IN_WORKGROUP_WORDS as u32)
            .count();
        assert_eq!(regions, 1, "{pass}: one obstacle region: {workgroup:?}");
        let bytes: u32 = workgroup.iter().map(|&(_, bytes)| bytes).sum();
        assert_eq!(
            bytes as usize,
            4 * wgsl::REBUILD_WORKGROUP_WORDS,
            "{pass}: the rebuild's workgroup memory: {workgroup:?}"
        );
    }
    for (name, state, _) in shipped_tables() {
        let words = wgsl::ObstacleScratch::of(&state.columns()).words;
        assert!(
            words <= wgsl::OBSTACLES_IN_WORKGROUP_WORDS,
            "{name}: {words} words of obstacle region"
        );
    }
}

/// A fused pass (`schedule::fused_passes`) holds stages of the step that one lane can run in a row:
/// batch shaders in the order of `pipeline::STAGES` with nothing between them but the stages only
/// the SNGNN-v2 reward runs (so a step without it runs the pass in one dispatch), none with rare
/// work queued across environments, none that builds SNGNN graphs, each in one pass, at most
/// `schedule::MAX_FUSED_MEMBERS` of them, at most `schedule::MAX_ORCA_STAGES_PER_PASS` that run ORCA;
/// and each member's bit selects it alone.
#[test]
fn fused_passes_hold_consecutive_stages_of_one_environment() {
    use socnav::pipeline::{STAGES, Shader};
    let index = |name: &str| STAGES.iter().position(|s| s.name == name).expect("a stage");
    let runs_orca = |m: &str| {
        let file = wgsl::source(&format!("{m}.wgsl")).expect("a stage shader");
        file.contains("orca_world_velocity(")
    };
    assert_eq!(
        STAGES
            .iter()
            .filter(|s| s.shader == Shader::Batch && runs_orca(s.name))
            .count(),
        3,
        "the stages that run ORCA: shadow_robot, group_velocities, human_motion"
    );
    let mut seen = Vec::new();
    for (pass, members) in schedule::fused_passes() {
        assert!(members.len() <= schedule::MAX_FUSED_MEMBERS, "{pass}");
        assert!(!members.is_empty(), "{pass}");
        let orca = members.iter().filter(|m| runs_orca(m)).count();
        assert!(
            orca <= schedule::MAX_ORCA_STAGES_PER_PASS,
            "{pass}: {orca} stages run ORCA"
        );
        for (bit, m) in members.iter().enumerate() {
            let s = &STAGES[index(m)];
            assert_eq!(s.shader, Shader::Batch, "{pass}: {m}");
            assert!(!s.sngnn_reward_only && !s.gpu.rare_work, "{pass}: {m}");
            assert!(!seen.contains(m), "{m} is in two fused passes");
            seen.push(*m);
            assert_eq!(schedule::fused_pass_of(m), Some((pass, bit as u32)));
            assert_eq!(schedule::pass_of(m), pass);
        }
        for pair in members.windows(2) {
            let (a, b) = (index(pair[0]), index(pair[1]));
            assert!(a < b, "{pass}: {} before {}", pair[0], pair[1]);
            assert!(
                STAGES[a + 1..b].iter().all(|s| s.sngnn_reward_only),
                "{pass}: a stage of every step comes between {} and {}",
                pair[0],
                pair[1]
            );
        }
    }
    assert_eq!(schedule::pass_of("begin_step"), "begin_step");
    assert_eq!(
        schedule::pass_of(schedule::RESET_PASS),
        schedule::RESET_PASS
    );
}
