//! Loading `SOCNAV_V2.tch`, the PyTorch state dict of SNGNN-v2, without PyTorch.
//!
//! The file is a zip (`torch.save`'s format since PyTorch 1.6): `<prefix>/data.pkl` pickles an
//! `OrderedDict` of tensor name → `torch._utils._rebuild_tensor_v2(storage, offset, size, stride,
//! ...)`, each storage a persistent id `('storage', torch.FloatStorage, key, location, numel)`
//! whose raw little-endian float32 values are the entry `<prefix>/data/<key>`. A strict pickle VM
//! (`pickle.rs`) reads the dict; every name and shape is then checked against docs/spec.md 7.1, and
//! every problem found is reported at once. Values are copied bit for bit (denormals included).

use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::{BufReader, Read, Seek};
use std::path::Path;

use zip::ZipArchive;

use super::pickle::{self, TensorRef, Value};
use super::{EDGE_FEATURES, Tensor, Weights};
use crate::SimError;

/// One edge-conditioned convolution (DGL `NNConv`) of the model: `inputs → outputs` node
/// features, its edge network `Linear(18→hidden[0]) → ReLU → Linear(→hidden[1]) → ReLU →
/// Linear(→inputs·outputs)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Layer {
    /// State-dict prefix of the layer's tensors.
    pub name: &'static str,
    /// Node features in.
    pub inputs: usize,
    /// Node features out.
    pub outputs: usize,
    /// Widths of the edge network's two hidden layers: ⌊18·0.666 + in·out·0.334⌋ and
    /// ⌊18·0.334 + in·out·0.666⌋ (docs/spec.md 7.1).
    pub hidden: [usize; 2],
}

/// The six layers in order (docs/spec.md 7.1: 42 → 40 → 30 → 21 → 12 → 3 → 2).
pub const LAYERS: [Layer; 6] = [
    layer("gnn_object.NNconv_input", 42, 40, [573, 1124]),
    layer("gnn_object.layers.0", 40, 30, [412, 805]),
    layer("gnn_object.layers.1", 30, 21, [222, 425]),
    layer("gnn_object.layers.2", 21, 12, [96, 173]),
    layer("gnn_object.layers.3", 12, 3, [24, 29]),
    layer("gnn_object.NNConv_output", 3, 2, [13, 10]),
];

/// Parameters of the model, all tensors together (docs/spec.md 7.1).
pub const PARAMETERS: usize = 4_286_204;

/// The state-dict file inside the socnavgym 0.1.1 wheel.
pub const WHEEL_ENTRY: &str = "socnavgym/envs/utils/sngnnv2/example_model/SOCNAV_V2.tch";

/// The largest `data.pkl` accepted: the real one is 7,905 bytes. This limit and the next only
/// stop a hostile file from making the loader allocate without bound.
const MAX_PICKLE_BYTES: u64 = 1 << 20;
/// The largest storage accepted: the whole model is 17 MB.
const MAX_STORAGE_BYTES: u64 = 1 << 26;

const fn layer(name: &'static str, inputs: usize, outputs: usize, hidden: [usize; 2]) -> Layer {
    Layer {
        name,
        inputs,
        outputs,
        hidden,
    }
}

impl Layer {
    /// The layer's seven tensors with their shapes, in the state dict's order.
    pub fn tensors(&self) -> [(String, Vec<usize>); 7] {
        let [a, b] = self.hidden;
        let w = self.inputs * self.outputs;
        let name = |suffix: &str| format!("{}.{suffix}", self.name);
        [
            (name("bias"), vec![self.outputs]),
            (name("edge_func.0.weight"), vec![a, EDGE_FEATURES]),
            (name("edge_func.0.bias"), vec![a]),
            (name("edge_func.2.weight"), vec![b, a]),
            (name("edge_func.2.bias"), vec![b]),
            (name("edge_func.4.weight"), vec![w, b]),
            (name("edge_func.4.bias"), vec![w]),
        ]
    }
}

/// Every tensor of the model by name, with its shape (docs/spec.md 7.1's table).
pub fn expected_tensors() -> BTreeMap<String, Vec<usize>> {
    LAYERS.iter().flat_map(Layer::tensors).collect()
}

impl Weights {
    /// Load and check the state dict at `path`.
    pub fn load(path: &Path) -> Result<Self, SimError> {
        let source = path.display().to_string();
        let file =
            File::open(path).map_err(|e| SimError::Sngnn(format!("cannot open {source}: {e}")))?;
        Self::read(BufReader::new(file), &source)
    }

    /// Read and check a state dict from `reader`; `source` names it in error messages.
    pub fn read<R: Read + Seek>(reader: R, source: &str) -> Result<Self, SimError> {
        let fail = |problems: Vec<String>| SimError::Sngnn(report(source, &problems));
        let mut zip = ZipArchive::new(reader).map_err(|e| {
            fail(vec![format!(
                "not a zip archive (torch.save writes one), or a damaged one: {e}"
            )])
        })?;
        let prefix = archive_prefix(&zip).map_err(|p| fail(vec![p]))?;
        let pickled = read_entry(&mut zip, &format!("{prefix}/data.pkl"), MAX_PICKLE_BYTES)
            .map_err(|p| fail(vec![p]))?;
        let root = pickle::load(&pickled).map_err(|p| fail(vec![p]))?;
        let entries = state_dict_entries(root).map_err(fail)?;
        let (wanted, mut problems) = check_names_and_shapes(&entries);
        let mut tensors = BTreeMap::new();
        for (name, t) in wanted {
            match read_tensor(&mut zip, &prefix, t) {
                Ok(tensor) => {
                    tensors.insert(name.clone(), tensor);
                }
                Err(p) => problems.push(format!("tensor `{name}`: {p}")),
            }
        }
        if problems.is_empty() {
            Ok(Weights { tensors })
        } else {
            Err(fail(problems))
        }
    }

    /// Number of parameters over every tensor.
    pub fn parameters(&self) -> usize {
        self.tensors.values().map(|t| t.data.len()).sum()
    }
}

/// `<source>: <problem>`, or every problem on its own line.
fn report(source: &str, problems: &[String]) -> String {
    match problems {
        [one] => format!("{source}: {one}"),
        many => format!(
            "{source}: {} problems:\n  - {}",
            many.len(),
            many.join("\n  - ")
        ),
    }
}

/// The directory that holds `data.pkl`: `archive` for older PyTorch, the file's stem for newer.
fn archive_prefix<R: Read + Seek>(zip: &ZipArchive<R>) -> Result<String, String> {
    let candidates: Vec<&str> = zip
        .file_names()
        .filter_map(|n| n.strip_suffix("/data.pkl"))
        .filter(|p| !p.is_empty() && !p.contains('/'))
        .collect();
    match candidates.as_slice() {
        [one] => Ok((*one).to_owned()),
        [] => Err("no `<dir>/data.pkl` in the archive: not a PyTorch state dict".into()),
        many => Err(format!("several state dicts in one archive: {many:?}")),
    }
}

/// The bytes of entry `name`, refused when larger than `limit` (before reading it).
fn read_entry<R: Read + Seek>(
    zip: &mut ZipArchive<R>,
    name: &str,
    limit: u64,
) -> Result<Vec<u8>, String> {
    let entry = zip
        .by_name(name)
        .map_err(|e| format!("entry {name}: {e}"))?;
    let size = entry.size();
    if size > limit {
        return Err(format!(
            "entry {name} has {size} bytes, more than the {limit} expected"
        ));
    }
    let mut bytes = Vec::with_capacity(size as usize);
    // `take` guards against a size field that lies; the length is checked below.
    entry
        .take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("entry {name}: {e}"))?;
    if bytes.len() as u64 != size {
        return Err(format!(
            "entry {name}: {} bytes where its header says {size}",
            bytes.len()
        ));
    }
    Ok(bytes)
}

/// The pickled object as (name, tensor) pairs: it must be a dict of str → tensor.
fn state_dict_entries(root: Value) -> Result<Vec<(String, TensorRef)>, Vec<String>> {
    let Value::Dict(entries, _) = root else {
        return Err(vec![format!(
            "data.pkl holds a {}, not a state dict",
            root.kind()
        )]);
    };
    let mut tensors = Vec::with_capacity(entries.len());
    let mut problems = Vec::new();
    for (key, value) in entries {
        match (key, value) {
            (Value::Str(name), Value::Tensor(t)) => tensors.push((name.to_string(), (*t).clone())),
            (key, value) => problems.push(format!(
                "state-dict entry {} → {} is not name → tensor",
                key.kind(),
                value.kind()
            )),
        }
    }
    if problems.is_empty() {
        Ok(tensors)
    } else {
        Err(problems)
    }
}

/// The entries whose names and shapes are docs/spec.md 7.1's, and every missing, unexpected,
/// repeated or misshapen tensor.
fn check_names_and_shapes(
    entries: &[(String, TensorRef)],
) -> (Vec<(&String, &TensorRef)>, Vec<String>) {
    let expected = expected_tensors();
    let mut wanted = Vec::new();
    let mut problems = Vec::new();
    let mut seen = BTreeSet::new();
    for (name, t) in entries {
        if !seen.insert(name.as_str()) {
            problems.push(format!("tensor `{name}` appears twice"));
            continue;
        }
        match expected.get(name) {
            None => problems.push(format!(
                "unexpected tensor `{name}` (not in docs/spec.md 7.1)"
            )),
            Some(shape) if !same_shape(shape, &t.size) => problems.push(format!(
                "tensor `{name}` has shape {:?} where docs/spec.md 7.1 has {shape:?}",
                t.size
            )),
            Some(_) => wanted.push((name, t)),
        }
    }
    for name in expected.keys() {
        if !seen.contains(name.as_str()) {
            problems.push(format!("tensor `{name}` is missing"));
        }
    }
    (wanted, problems)
}

fn same_shape(expected: &[usize], size: &[u64]) -> bool {
    expected.len() == size.len() && expected.iter().zip(size).all(|(&e, &s)| e as u64 == s)
}

/// The values of one contiguous tensor from its storage blob.
#[expect(clippy::expect_used, reason = "chunks_exact(4) yields 4 bytes")]
fn read_tensor<R: Read + Seek>(
    zip: &mut ZipArchive<R>,
    prefix: &str,
    t: &TensorRef,
) -> Result<Tensor, String> {
    let numel = contiguous_numel(&t.size, &t.stride)?;
    let end = t
        .offset
        .checked_add(numel)
        .filter(|&e| e <= t.storage.numel);
    let end = end.ok_or_else(|| {
        format!(
            "{numel} elements from offset {} lie outside storage {} of {} elements",
            t.offset, t.storage.key, t.storage.numel
        )
    })?;
    // A tensor may view part of a larger storage, but none of this model comes near the limit.
    let bytes = t.storage.numel.saturating_mul(4);
    if bytes > MAX_STORAGE_BYTES {
        return Err(format!(
            "storage {} of {} elements is larger than the whole model",
            t.storage.key, t.storage.numel
        ));
    }
    let blob = read_entry(zip, &format!("{prefix}/data/{}", t.storage.key), bytes)?;
    if blob.len() as u64 != bytes {
        return Err(format!(
            "storage {} has {} bytes, {} float32 values need {bytes}",
            t.storage.key,
            blob.len(),
            t.storage.numel
        ));
    }
    // In range of the blob just read, whose length fits usize.
    let values = &blob[t.offset as usize * 4..end as usize * 4];
    Ok(Tensor {
        shape: t.size.iter().map(|&s| s as usize).collect(),
        data: values
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect(),
    })
}

/// The element count of a row-major contiguous tensor, or why its strides are not contiguous.
fn contiguous_numel(size: &[u64], stride: &[u64]) -> Result<u64, String> {
    if size.len() != stride.len() {
        return Err(format!(
            "size {size:?} and stride {stride:?} differ in rank"
        ));
    }
    let mut expected = 1u64;
    for (&s, &st) in size.iter().zip(stride).rev() {
        // A dimension of extent 1 may carry any stride (PyTorch does not normalise them).
        if s != 1 && st != expected {
            return Err(format!(
                "strides {stride:?} for size {size:?} are not row-major contiguous"
            ));
        }
        expected = expected.checked_mul(s).ok_or("element count overflows")?;
    }
    Ok(expected)
}
