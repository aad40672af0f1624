//! Writing PyTorch state-dict zips the way `torch.save` does (pickle protocol 2: an
//! `OrderedDict` of `_rebuild_tensor_v2` calls over persistent storage ids, raw float32 blobs
//! under `<prefix>/data/<key>`), so that the SNGNN loader can be tested on synthetic files: the
//! real weights are GPL-3.0 and never part of the repository. The opcode sequence copies the real
//! file's (see `pickletools.dis`), memo references included.

use std::io::{Cursor, Write};

use zip::CompressionMethod;
use zip::write::SimpleFileOptions;

/// One tensor of a state dict: a view (`offset`, `size`, `stride`, in elements) into the storage
/// `key` of `numel` elements.
#[derive(Debug, Clone)]
pub struct Entry {
    pub name: String,
    pub key: String,
    /// The storage class (`FloatStorage` for float32).
    pub storage_type: String,
    pub numel: u64,
    pub offset: u64,
    pub size: Vec<u64>,
    pub stride: Vec<u64>,
}

impl Entry {
    /// A contiguous tensor of `shape` filling its own storage `key`.
    pub fn contiguous(name: &str, key: &str, shape: &[usize]) -> Self {
        let size: Vec<u64> = shape.iter().map(|&s| s as u64).collect();
        let mut stride = vec![1u64; size.len()];
        for d in (0..size.len().saturating_sub(1)).rev() {
            stride[d] = stride[d + 1] * size[d + 1];
        }
        Entry {
            name: name.into(),
            key: key.into(),
            storage_type: "FloatStorage".into(),
            numel: size.iter().product(),
            offset: 0,
            size,
            stride,
        }
    }
}

/// Pickle opcodes, appended to a byte buffer.
#[derive(Debug, Default)]
pub struct Pickler {
    pub out: Vec<u8>,
}

impl Pickler {
    pub fn op(&mut self, op: u8) -> &mut Self {
        self.out.push(op);
        self
    }

    pub fn proto(&mut self) -> &mut Self {
        self.op(0x80).op(2)
    }

    pub fn global(&mut self, module: &str, name: &str) -> &mut Self {
        self.op(b'c');
        self.out
            .extend_from_slice(format!("{module}\n{name}\n").as_bytes());
        self
    }

    pub fn str(&mut self, s: &str) -> &mut Self {
        self.op(b'X');
        self.out.extend_from_slice(&(s.len() as u32).to_le_bytes());
        self.out.extend_from_slice(s.as_bytes());
        self
    }

    /// An integer with the smallest opcode torch's pickler would use.
    pub fn int(&mut self, v: u64) -> &mut Self {
        match v {
            0..=0xff => self.op(b'K').op(v as u8),
            0x100..=0xffff => {
                self.op(b'M');
                self.out.extend_from_slice(&(v as u16).to_le_bytes());
                self
            }
            _ if v <= i32::MAX as u64 => {
                self.op(b'J');
                self.out.extend_from_slice(&(v as i32).to_le_bytes());
                self
            }
            _ => {
                self.op(0x8a).op(8);
                self.out.extend_from_slice(&v.to_le_bytes());
                self
            }
        }
    }

    pub fn tuple_of(&mut self, values: &[u64]) -> &mut Self {
        self.op(b'(');
        for &v in values {
            self.int(v);
        }
        self.op(b't')
    }

    pub fn put(&mut self, i: u8) -> &mut Self {
        self.op(b'q').op(i)
    }

    pub fn get(&mut self, i: u8) -> &mut Self {
        self.op(b'h').op(i)
    }
}

/// `data.pkl` of a state dict holding `entries`, as torch writes it: memo 0 is
/// `collections.OrderedDict`, memo 1 the dict itself, memo 2 `_rebuild_tensor_v2`; the dict's
/// `_metadata` attribute is set by BUILD at the end.
pub fn state_dict_pickle(entries: &[Entry]) -> Vec<u8> {
    let mut p = Pickler::default();
    p.proto().global("collections", "OrderedDict").put(0);
    p.op(b')').op(b'R').put(1).op(b'(');
    for (i, e) in entries.iter().enumerate() {
        p.str(&e.name);
        if i == 0 {
            p.global("torch._utils", "_rebuild_tensor_v2").put(2);
        } else {
            p.get(2);
        }
        p.op(b'(')
            .op(b'(')
            .str("storage")
            .global("torch", &e.storage_type);
        p.str(&e.key).str("cuda:0").int(e.numel).op(b't').op(b'Q');
        p.int(e.offset).tuple_of(&e.size).tuple_of(&e.stride);
        // requires_grad False, backward hooks OrderedDict().
        p.op(0x89).get(0).op(b')').op(b'R').op(b't').op(b'R');
    }
    p.op(b'u');
    p.op(b'}').str("_metadata").get(0).op(b')').op(b'R');
    p.op(b'(')
        .str("")
        .op(b'}')
        .str("version")
        .int(1)
        .op(b's')
        .op(b'u');
    p.op(b's').op(b'b').op(b'.');
    p.out
}

/// A zip with `files` (name, bytes), stored or deflated.
pub fn zip_of(files: &[(String, Vec<u8>)], method: CompressionMethod) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let options = SimpleFileOptions::default().compression_method(method);
    for (name, bytes) in files {
        w.start_file(name.as_str(), options).unwrap();
        w.write_all(bytes).unwrap();
    }
    w.finish().unwrap().into_inner()
}

/// A state-dict zip under `prefix`: `data.pkl` from `pickle`, `version`, and one blob per
/// (key, values).
pub fn torch_zip(prefix: &str, pickle: Vec<u8>, blobs: &[(String, Vec<f32>)]) -> Vec<u8> {
    let mut files = vec![
        (format!("{prefix}/data.pkl"), pickle),
        (format!("{prefix}/version"), b"3\n".to_vec()),
    ];
    for (key, values) in blobs {
        let bytes = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        files.push((format!("{prefix}/data/{key}"), bytes));
    }
    zip_of(&files, CompressionMethod::Stored)
}
