//! The SNGNN-v2 weight loader (`socnav::sngnn`): the real `SOCNAV_V2.tch` against values read
//! independently with numpy, synthetic torch-format files for the success path, and every kind
//! of bad input (truncated, not a zip, no `data.pkl`, wrong names and shapes, strides, storages,
//! hostile pickles), which must give an error naming the problem, never a panic.
//!
//! The real file is GPL-3.0 and never in the repository: its tests use the file
//! `sngnn::weights_path` resolves (install it with `socnav sngnn install`) and skip loudly
//! without it, unless `REQUIRE_SNGNN=1` (CI sets it once the install succeeded).

use crate::common;

use std::io::Cursor;
use std::path::{Path, PathBuf};

use common::sngnn::real_weights;
use common::torch_zip::{Entry, Pickler, state_dict_pickle, torch_zip, zip_of};
use socnav::SimError;
use socnav::sngnn::{self, PARAMETERS, WHEEL_ENTRY, Weights, expected_tensors};
use zip::CompressionMethod;

fn bits(values: &[f32]) -> Vec<u32> {
    values.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn real_file_has_spec_names_shapes_and_parameters() {
    let Some(w) = real_weights() else { return };
    assert_eq!(w.tensors.len(), 42);
    for (name, shape) in expected_tensors() {
        assert_eq!(w.get(&name).shape, shape, "{name}");
    }
    assert_eq!(w.parameters(), PARAMETERS);
}

/// Reference values read with numpy from the same file (`torch.load` is not needed for that:
/// the blobs are raw float32).
#[test]
fn real_file_matches_numpy() {
    let Some(w) = real_weights() else { return };
    let bias = w.get("gnn_object.NNConv_output.bias");
    let expected = [
        0.10928449779748917f64 as f32,
        0.029339462518692017f64 as f32,
    ];
    assert_eq!(bits(&bias.data), bits(&expected));
    let t = w.get("gnn_object.NNconv_input.edge_func.4.weight");
    assert_eq!(t.shape, [1680, 1124]);
    // Denormals: their bits must survive (no flush to zero).
    assert_eq!(
        t.data[0].to_bits(),
        (-5.1736317653457614e-39f64 as f32).to_bits()
    );
    let last = *t.data.last().unwrap();
    assert_eq!(last.to_bits(), (-5.907516994485026e-39f64 as f32).to_bits());
    let sum: f64 = t.data.iter().map(|&v| f64::from(v)).sum();
    // numpy sums pairwise, this sums in order: over 1.9 M terms the two f64 roundings differ by
    // 1.5e-11 here (the exact sum is -4075.288415170822); any changed element would move the
    // sum by far more than 1e-9, except a denormal, which the bit checks above cover.
    assert!((sum - -4075.2884151708217).abs() < 1e-9, "sum {sum}");
}

/// A value for element `i` of tensor `t` whose bits cover signs, denormals, infinities and NaN
/// payloads: the loader must copy bits, not values.
fn value(t: usize, i: usize) -> f32 {
    f32::from_bits((t as u32 + 1).wrapping_mul(0x9E37_79B9) ^ (i as u32).wrapping_mul(0x85EB_CA6B))
}

/// A synthetic state dict with every tensor of docs/spec.md 7.1: its zip and its tensors' values.
fn synthetic_model(prefix: &str) -> (Vec<u8>, Vec<(String, Vec<f32>)>) {
    let mut entries = Vec::new();
    let mut blobs = Vec::new();
    for (t, (name, shape)) in expected_tensors().into_iter().enumerate() {
        let key = format!("{}", 1000 + t);
        entries.push(Entry::contiguous(&name, &key, &shape));
        let n: usize = shape.iter().product();
        blobs.push((key, (0..n).map(|i| value(t, i)).collect::<Vec<f32>>()));
    }
    let names = entries.iter().map(|e| e.name.clone());
    let values = names.zip(blobs.iter().map(|(_, v)| v.clone())).collect();
    (
        torch_zip(prefix, state_dict_pickle(&entries), &blobs),
        values,
    )
}

#[test]
fn synthetic_model_loads_bit_for_bit() {
    // Older torch names the folder `archive`, newer ones after the file.
    for prefix in ["archive", "SOCNAV_V2"] {
        let (bytes, values) = synthetic_model(prefix);
        let w = Weights::read(Cursor::new(bytes), "synthetic").expect("loads");
        assert_eq!(w.parameters(), PARAMETERS);
        for (name, v) in &values {
            assert_eq!(bits(&w.get(name).data), bits(v), "{name}");
            assert_eq!(w.get(name).shape, expected_tensors()[name]);
        }
    }
}

/// The message of a load that must fail.
fn error_of(bytes: Vec<u8>) -> String {
    match Weights::read(Cursor::new(bytes), "bad.tch") {
        Ok(_) => panic!("bad input loaded"),
        Err(SimError::Sngnn(m)) => m,
        Err(e) => panic!("not an Sngnn error: {e:?}"),
    }
}

#[test]
fn not_a_zip_empty_or_truncated() {
    assert!(error_of(b"PK\x03\x04 certainly not".to_vec()).contains("not a zip archive"));
    assert!(error_of(Vec::new()).contains("not a zip archive"));
    let (bytes, _) = synthetic_model("archive");
    for keep in [10, bytes.len() / 2, bytes.len() - 30, bytes.len() - 1] {
        let m = error_of(bytes[..keep].to_vec());
        assert!(m.starts_with("bad.tch: "), "{m}");
    }
    // A damaged blob: the zip's checksum catches it.
    let mut damaged = bytes.clone();
    damaged[bytes.len() / 2] ^= 0x40;
    let m = error_of(damaged);
    assert!(
        m.contains("entry archive/data/") && m.contains("checksum"),
        "{m}"
    );
}

#[test]
fn zip_without_data_pkl() {
    let bytes = zip_of(
        &[("archive/version".into(), b"3\n".to_vec())],
        CompressionMethod::Stored,
    );
    assert!(error_of(bytes).contains("no `<dir>/data.pkl`"));
}

/// A state dict of the given entries whose blobs are the right size, zeros.
fn zip_with(entries: &[Entry]) -> Vec<u8> {
    let blobs: Vec<(String, Vec<f32>)> = entries
        .iter()
        .map(|e| (e.key.clone(), vec![0.0; e.numel as usize]))
        .collect();
    torch_zip("archive", state_dict_pickle(entries), &blobs)
}

/// docs/spec.md 7.1's entries, each on its own storage.
fn spec_entries() -> Vec<Entry> {
    let tensors = expected_tensors().into_iter().enumerate();
    tensors
        .map(|(t, (name, shape))| Entry::contiguous(&name, &t.to_string(), &shape))
        .collect()
}

#[test]
fn every_name_and_shape_problem_is_reported_at_once() {
    let mut entries = spec_entries();
    entries.retain(|e| e.name != "gnn_object.layers.1.bias");
    entries[0] = Entry::contiguous(&entries[0].name, "900", &[41]);
    entries[5] = Entry::contiguous(&entries[5].name, "901", &[7, 7]);
    entries.push(Entry::contiguous("gnn_object.extra.weight", "902", &[2]));
    let m = error_of(zip_with(&entries));
    assert!(m.starts_with("bad.tch: 4 problems:"), "{m}");
    for part in [
        "tensor `gnn_object.NNConv_output.bias` has shape [41] where docs/spec.md 7.1 has [2]",
        "has shape [7, 7] where",
        "unexpected tensor `gnn_object.extra.weight`",
        "tensor `gnn_object.layers.1.bias` is missing",
    ] {
        assert!(m.contains(part), "{part:?} not in {m}");
    }
}

/// The entry called `name`.
fn named<'a>(entries: &'a mut [Entry], name: &str) -> &'a mut Entry {
    entries.iter_mut().find(|e| e.name == name).unwrap()
}

#[test]
fn strides_offsets_and_storages_are_checked() {
    let mut entries = spec_entries();
    let mut blobs: Vec<(String, Vec<f32>)> = entries
        .iter()
        .map(|e| (e.key.clone(), vec![0.0; e.numel as usize]))
        .collect();
    named(&mut entries, "gnn_object.layers.0.edge_func.2.weight")
        .stride
        .reverse();
    named(&mut entries, "gnn_object.layers.0.bias").offset = 1;
    // The storage claims one element more than its blob holds.
    let short = named(&mut entries, "gnn_object.layers.1.bias");
    short.numel += 1;
    let short = short.key.clone();
    let gone = named(&mut entries, "gnn_object.layers.2.bias").key.clone();
    blobs.retain(|(k, _)| *k != gone);
    let m = error_of(torch_zip("archive", state_dict_pickle(&entries), &blobs));
    assert!(m.starts_with("bad.tch: 4 problems:"), "{m}");
    for part in [
        "tensor `gnn_object.layers.0.edge_func.2.weight`: strides [1, 412] for size [805, 412] \
         are not row-major contiguous"
            .to_string(),
        "tensor `gnn_object.layers.0.bias`: 30 elements from offset 1 lie outside storage".into(),
        format!("tensor `gnn_object.layers.1.bias`: storage {short} has 84 bytes, 22 float32"),
        format!("tensor `gnn_object.layers.2.bias`: entry archive/data/{gone}"),
    ] {
        assert!(m.contains(&part), "{part:?} not in {m}");
    }
}

/// The message of loading a zip whose `data.pkl` is `pickle` (and no blobs).
fn pickle_error(pickle: Vec<u8>) -> String {
    error_of(torch_zip("archive", pickle, &[]))
}

#[test]
fn hostile_or_foreign_pickles_are_refused() {
    let mut p = Pickler::default();
    p.proto()
        .global("os", "system")
        .str("echo hi")
        .op(0x85)
        .op(b'R')
        .op(b'.');
    assert!(pickle_error(p.out).contains("global os.system is not part of a float32 state dict"));

    let mut entries = spec_entries();
    entries[0].storage_type = "LongStorage".into();
    assert!(error_of(zip_with(&entries)).contains("torch.LongStorage: only float32"));

    let mut p = Pickler::default();
    p.op(0x80).op(4).op(b'N').op(b'.');
    assert!(pickle_error(p.out).contains("pickle protocol 4"));

    // A length far beyond the file must not be allocated.
    let mut p = Pickler::default();
    p.proto().op(b'X');
    p.out.extend_from_slice(&u32::MAX.to_le_bytes());
    assert!(pickle_error(p.out).contains("truncated"));

    // Deep nesting must not recurse (dropping a million nested tuples would overflow the stack).
    let mut p = Pickler::default();
    p.proto().op(b')');
    for _ in 0..1_000_000 {
        p.op(0x85);
    }
    p.op(b'.');
    assert!(pickle_error(p.out).contains("nested deeper"));

    // Not a dict of tensors.
    let mut p = Pickler::default();
    p.proto().op(b'}').str("a").int(1).op(b's').op(b'.');
    assert!(pickle_error(p.out).contains("str \"a\" → int 1 is not name → tensor"));
}

/// Every prefix of a valid pickle, and every single-byte change from a set of opcodes, gives
/// an error or a value, never a panic.
#[test]
fn damaged_pickles_never_panic() {
    let entries = [
        Entry::contiguous("gnn_object.NNConv_output.bias", "1", &[2]),
        Entry::contiguous("gnn_object.layers.3.edge_func.2.weight", "2", &[29, 24]),
    ];
    let pickle = state_dict_pickle(&entries);
    let blobs = [
        ("1".to_string(), vec![0.0; 2]),
        ("2".to_string(), vec![0.0; 29 * 24]),
    ];
    for len in 0..pickle.len() {
        let m = error_of(torch_zip("archive", pickle[..len].to_vec(), &blobs));
        assert!(m.contains("data.pkl"), "{m}");
    }
    let ops = [
        0x00, 0xff, b'(', b')', b't', b'R', b'Q', b'b', b'h', b'q', b'X', 0x8a, b'.', b'u',
    ];
    for i in 0..pickle.len() {
        for &op in &ops {
            let mut damaged = pickle.clone();
            damaged[i] = op;
            // Two tensors are not the model: any outcome but a panic is an error.
            let _ = error_of(torch_zip("archive", damaged, &blobs));
        }
    }
}

/// A fresh directory for one test.
fn temp_dir(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("socnav-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A wheel (a deflated zip) holding `weights` where socnavgym 0.1.1 keeps them.
fn wheel_with(dir: &Path, weights: Vec<u8>) -> PathBuf {
    let wheel = dir.join("socnavgym-0.1.1-py3-none-any.whl");
    let files = [
        ("socnavgym/__init__.py".to_string(), b"".to_vec()),
        (WHEEL_ENTRY.to_string(), weights),
    ];
    std::fs::write(&wheel, zip_of(&files, CompressionMethod::Deflated)).unwrap();
    wheel
}

#[test]
fn install_from_wheel_is_checked_and_atomic() {
    let dir = temp_dir("sngnn-install");
    let dest = dir.join("cache").join(sngnn::CACHE_FILE);
    let (bytes, _) = synthetic_model("archive");
    let w = sngnn::install_from_wheel(&wheel_with(&dir, bytes.clone()), &dest).unwrap();
    assert_eq!(w.parameters(), PARAMETERS);
    assert_eq!(std::fs::read(&dest).unwrap(), bytes);

    // A bad file in the wheel leaves the installed one alone and no partial file behind.
    let bad = wheel_with(&dir, b"not a state dict".to_vec());
    let e = sngnn::install_from_wheel(&bad, &dest).unwrap_err();
    assert!(e.to_string().contains("not a zip archive"), "{e}");
    assert_eq!(std::fs::read(&dest).unwrap(), bytes);
    let left: Vec<_> = std::fs::read_dir(dest.parent().unwrap()).unwrap().collect();
    assert_eq!(left.len(), 1, "{left:?}");

    let no_entry = dir.join("other.whl");
    std::fs::write(&no_entry, zip_of(&[], CompressionMethod::Stored)).unwrap();
    let e = sngnn::install_from_wheel(&no_entry, &dest).unwrap_err();
    assert!(e.to_string().contains(WHEEL_ENTRY), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn missing_files_say_how_to_install() {
    let e = Weights::load(Path::new("no/such/SOCNAV_V2.tch")).unwrap_err();
    assert!(
        e.to_string().contains("cannot open no/such/SOCNAV_V2.tch"),
        "{e}"
    );
    assert!(sngnn::install_hint().contains("socnav sngnn install"));
    // The variable would win over the config value given here.
    if std::env::var_os(sngnn::WEIGHTS_ENV).is_none() {
        let e = sngnn::load_weights(Some("no/such/SOCNAV_V2.tch")).unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("no weight file at no/such/SOCNAV_V2.tch (from the config"),
            "{m}"
        );
        assert!(m.contains("socnav sngnn install"), "{m}");
    }
}

/// `socnav sngnn <args>` with the weight variables replaced by `env`: (status, stdout, stderr).
#[cfg(feature = "cli")]
fn socnav_sngnn(args: &[&str], env: &[(&str, &Path)]) -> (Option<i32>, String, String) {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_socnav"));
    cmd.arg("sngnn")
        .args(args)
        .env_remove(sngnn::WEIGHTS_ENV)
        .env_remove(sngnn::CACHE_ENV);
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().expect("socnav runs");
    let text = |b: Vec<u8>| String::from_utf8(b).unwrap();
    (out.status.code(), text(out.stdout), text(out.stderr))
}

#[cfg(feature = "cli")]
#[test]
fn cli_path_shows_the_resolved_file() {
    let dir = temp_dir("sngnn-cli-path");
    let file = dir.join("w.tch");
    std::fs::write(&file, b"1234").unwrap();
    let (code, out, _) = socnav_sngnn(&["path"], &[(sngnn::WEIGHTS_ENV, &file)]);
    assert_eq!(code, Some(0));
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], file.display().to_string());
    assert_eq!(lines[1], "source: from SOCNAV_SNGNN_WEIGHTS");
    assert_eq!(lines[2], "exists: yes (4 bytes)");

    let (code, out, _) = socnav_sngnn(&["path"], &[(sngnn::CACHE_ENV, &dir)]);
    assert_eq!(code, Some(0));
    let expected = dir.join("sngnn").join("SOCNAV_V2.tch");
    assert_eq!(
        out.lines().next(),
        Some(expected.display().to_string().as_str())
    );
    assert!(
        out.contains("exists: no (install with `socnav sngnn install`)"),
        "{out}"
    );

    let config = dir.join("c.toml");
    std::fs::write(&config, "[reward]\nsngnn_weights = \"x/w.tch\"\n").unwrap();
    let args = ["path", "--config", config.to_str().unwrap()];
    let (code, out, _) = socnav_sngnn(&args, &[]);
    assert_eq!(code, Some(0));
    assert!(
        out.starts_with("x/w.tch\nsource: from the config's reward.sngnn_weights\n"),
        "{out}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Without Python, install fails with exit status 3 (what CI reads as "skip") and says why.
#[cfg(feature = "cli")]
#[test]
fn cli_install_without_python_says_why() {
    let dir = temp_dir("sngnn-cli-install");
    let python = dir.join("no-python");
    let cache = dir.join("cache");
    let args = ["install", "--cache-dir", cache.to_str().unwrap()];
    let (code, _, err) = socnav_sngnn(&args, &[("SOCNAV_PYTHON", &python)]);
    assert_eq!(code, Some(3), "{err}");
    assert!(
        err.contains("not found: install Python 3 with pip"),
        "{err}"
    );
    assert!(!cache.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}
