//! A strict pickle VM for the `data.pkl` of a PyTorch state dict (`torch.save`, pickle protocol 2).
//!
//! A pickle is a program: it may name and call any Python callable. This VM runs only the opcodes
//! `torch.save` emits for a dict of float32 tensors, and knows only three globals
//! (`collections.OrderedDict`, `torch._utils._rebuild_tensor_v2`, `torch.FloatStorage`); anything
//! else is an error that names the opcode or global and its byte position, never a panic.
//!
//! Hostile input stays cheap: lengths are checked against the bytes left before anything is
//! allocated, values are shared (`Rc`) so that memo copies cost O(1), containers nest at most
//! [`MAX_DEPTH`] deep (no deep recursion when dropping), and a tensor has at most [`MAX_RANK`]
//! dimensions, so every opcode costs time in proportion to the bytes it consumes.
//!
//! Pickle's memo lets a later opcode refer to an earlier object, which Python shares. Here only
//! immutable values are shared; a dict may be filled after it is memoised, so fetching one from
//! the memo is refused rather than answered with a stale copy (torch never does it).

use std::collections::HashMap;
use std::rc::Rc;

/// Deepest nesting of tuples and dicts accepted; a state dict needs 3 (the `_metadata` dicts).
const MAX_DEPTH: u8 = 4;
/// Most dimensions of a tensor.
pub(crate) const MAX_RANK: usize = 8;

/// A value on the VM's stack.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    None,
    Bool(bool),
    Int(i64),
    Str(Rc<str>),
    /// A tuple and how deep containers nest in it.
    Tuple(Rc<[Value]>, u8),
    /// A dict or an `OrderedDict`: entries in insertion order, and how deep containers nest in it.
    Dict(Vec<(Value, Value)>, u8),
    Global(Global),
    Storage(Rc<Storage>),
    Tensor(Rc<TensorRef>),
}

/// The globals a float32 state dict names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Global {
    OrderedDict,
    RebuildTensorV2,
    FloatStorage,
}

/// A persistent storage reference: the float32 blob `<prefix>/data/<key>` of `numel` elements.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Storage {
    pub key: String,
    pub numel: u64,
}

/// A tensor as `_rebuild_tensor_v2` describes it: a view into a storage (offset and strides in
/// elements).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct TensorRef {
    pub storage: Rc<Storage>,
    pub offset: u64,
    pub size: Vec<u64>,
    pub stride: Vec<u64>,
}

impl Value {
    /// How deep containers nest in this value (0 for a scalar), as recorded when it was made.
    fn depth(&self) -> u8 {
        match self {
            Value::Tuple(_, depth) | Value::Dict(_, depth) => *depth,
            _ => 0,
        }
    }

    /// What the value is, for error messages (never the whole value: it may be large).
    pub(crate) fn kind(&self) -> String {
        match self {
            Value::None => "None".into(),
            Value::Bool(b) => format!("bool {b}"),
            Value::Int(i) => format!("int {i}"),
            Value::Str(s) if s.len() <= 80 => format!("str {s:?}"),
            Value::Str(s) => format!("str of {} bytes", s.len()),
            Value::Tuple(items, _) => format!("tuple of {}", items.len()),
            Value::Dict(entries, _) => format!("dict of {}", entries.len()),
            Value::Global(g) => format!("global {g:?}"),
            Value::Storage(s) => format!("storage {}", s.key),
            Value::Tensor(t) => format!("tensor on storage {}", t.storage.key),
        }
    }
}

/// Run the pickle `bytes` and return the object it builds.
pub(crate) fn load(bytes: &[u8]) -> Result<Value, String> {
    let mut vm = Vm {
        bytes,
        pos: 0,
        stack: Vec::new(),
        marks: Vec::new(),
        memo: HashMap::new(),
    };
    vm.run()
        .map_err(|e| format!("data.pkl byte {}: {e}", vm.pos))
}

struct Vm<'a> {
    bytes: &'a [u8],
    pos: usize,
    stack: Vec<Value>,
    /// Stack depths at each MARK, innermost last.
    marks: Vec<usize>,
    /// Memoised values; `None` for a dict, which cannot be fetched (see the module docs).
    memo: HashMap<u32, Option<Value>>,
}

impl Vm<'_> {
    fn run(&mut self) -> Result<Value, String> {
        loop {
            let op = self.byte()?;
            if op == b'.' {
                return self.finish();
            }
            self.step(op)?;
        }
    }

    /// STOP: exactly one object must be left, and nothing may follow.
    #[expect(
        clippy::expect_used,
        reason = "the stack's length is checked just above"
    )]
    fn finish(&mut self) -> Result<Value, String> {
        if self.pos != self.bytes.len() {
            return Err(format!("{} bytes after STOP", self.bytes.len() - self.pos));
        }
        if self.stack.len() != 1 || !self.marks.is_empty() {
            return Err(format!(
                "STOP with {} values and {} open marks",
                self.stack.len(),
                self.marks.len()
            ));
        }
        Ok(self.stack.pop().expect("one value"))
    }

    fn step(&mut self, op: u8) -> Result<(), String> {
        match op {
            0x80 => self.proto(),
            b'(' => {
                self.marks.push(self.stack.len());
                Ok(())
            }
            b'c' => self.global(),
            b'X' => self.unicode(),
            b'J' => {
                let v = i32::from_le_bytes(self.array()?);
                self.int(v)
            }
            b'K' => {
                let v = self.byte()?;
                self.int(v)
            }
            b'M' => {
                let v = u16::from_le_bytes(self.array()?);
                self.int(v)
            }
            0x8a => self.long1(),
            b'N' => self.push(Value::None),
            0x88 => self.push(Value::Bool(true)),
            0x89 => self.push(Value::Bool(false)),
            b')' => self.tuple(Vec::new()),
            b't' => {
                let items = self.pop_mark()?;
                self.tuple(items)
            }
            0x85..=0x87 => {
                let items = self.pop_n(usize::from(op - 0x84))?;
                self.tuple(items)
            }
            b'}' => self.push(Value::Dict(Vec::new(), 1)),
            b's' => {
                let items = self.pop_n(2)?;
                self.set_items(items)
            }
            b'u' => {
                let items = self.pop_mark()?;
                self.set_items(items)
            }
            b'q' | b'r' => {
                let index = self.memo_index(op)?;
                self.put(index)
            }
            b'h' | b'j' => {
                let index = self.memo_index(op)?;
                self.get(index)
            }
            b'Q' => {
                let pid = self.pop()?;
                self.push(Value::Storage(Rc::new(persistent_storage(&pid)?)))
            }
            b'R' => self.reduce(),
            b'b' => self.build(),
            other => Err(format!(
                "opcode {other:#04x} ({:?}) is not one torch.save writes for a state dict",
                char::from(other)
            )),
        }
    }

    fn proto(&mut self) -> Result<(), String> {
        match self.byte()? {
            2 => Ok(()),
            v => Err(format!(
                "pickle protocol {v}; torch.save writes protocol 2, the only one read here"
            )),
        }
    }

    /// GLOBAL: `module\nname\n`, one of the three a float32 state dict needs.
    fn global(&mut self) -> Result<(), String> {
        let module = self.line()?;
        let name = self.line()?;
        let global = match (module.as_str(), name.as_str()) {
            ("collections", "OrderedDict") => Global::OrderedDict,
            ("torch._utils", "_rebuild_tensor_v2") => Global::RebuildTensorV2,
            ("torch", "FloatStorage") => Global::FloatStorage,
            ("torch", s) if s.ends_with("Storage") => {
                return Err(format!(
                    "tensor storage torch.{s}: only float32 (torch.FloatStorage) is supported"
                ));
            }
            _ => {
                return Err(format!(
                    "global {module}.{name} is not part of a float32 state dict (refused: a \
                     pickle can name any Python callable)"
                ));
            }
        };
        self.push(Value::Global(global))
    }

    /// BINUNICODE: a u32 length, then UTF-8.
    fn unicode(&mut self) -> Result<(), String> {
        let n = self.u32()? as usize;
        let text = std::str::from_utf8(self.take(n)?).map_err(|e| format!("BINUNICODE: {e}"))?;
        let text = Rc::from(text);
        self.push(Value::Str(text))
    }

    fn int(&mut self, v: impl Into<i64>) -> Result<(), String> {
        self.push(Value::Int(v.into()))
    }

    /// LONG1: a little-endian two's-complement integer of up to 8 bytes.
    fn long1(&mut self) -> Result<(), String> {
        let n = usize::from(self.byte()?);
        if n > 8 {
            return Err(format!("LONG1 of {n} bytes does not fit 64 bits"));
        }
        let bytes = self.take(n)?;
        let fill = if bytes.last().is_some_and(|b| b & 0x80 != 0) {
            0xff
        } else {
            0
        };
        let mut full = [fill; 8];
        full[..n].copy_from_slice(bytes);
        self.int(i64::from_le_bytes(full))
    }

    fn tuple(&mut self, items: Vec<Value>) -> Result<(), String> {
        let depth = 1 + items.iter().map(Value::depth).max().unwrap_or(0);
        if depth > MAX_DEPTH {
            return Err(format!("containers nested deeper than {MAX_DEPTH}"));
        }
        self.push(Value::Tuple(Rc::from(items), depth))
    }

    fn set_items(&mut self, items: Vec<Value>) -> Result<(), String> {
        if !items.len().is_multiple_of(2) {
            return Err(format!(
                "SETITEMS with an odd number ({}) of values",
                items.len()
            ));
        }
        let Some(Value::Dict(entries, depth)) = self.stack.last_mut() else {
            return Err("SETITEM(S) on something that is not a dict".into());
        };
        let mut it = items.into_iter();
        while let (Some(k), Some(v)) = (it.next(), it.next()) {
            *depth = (*depth).max(1 + k.depth().max(v.depth()));
            if *depth > MAX_DEPTH {
                return Err(format!("containers nested deeper than {MAX_DEPTH}"));
            }
            entries.push((k, v));
        }
        Ok(())
    }

    /// REDUCE: call a known global with a tuple of arguments.
    fn reduce(&mut self) -> Result<(), String> {
        let args = self.pop()?;
        let callable = self.pop()?;
        let Value::Tuple(args, _) = args else {
            return Err(format!(
                "REDUCE arguments are a {}, not a tuple",
                args.kind()
            ));
        };
        let value = match callable {
            Value::Global(Global::OrderedDict) if args.is_empty() => Value::Dict(Vec::new(), 1),
            Value::Global(Global::RebuildTensorV2) => {
                Value::Tensor(Rc::new(rebuild_tensor(&args)?))
            }
            other => {
                return Err(format!(
                    "REDUCE calls {} with {} arguments",
                    other.kind(),
                    args.len()
                ));
            }
        };
        self.push(value)
    }

    /// BUILD: torch sets the state dict's `_metadata` attribute (module versions) this way; the
    /// attribute is not needed, so a dict state on a dict is accepted and dropped.
    fn build(&mut self) -> Result<(), String> {
        let state = self.pop()?;
        match (self.stack.last(), &state) {
            (Some(Value::Dict(..)), Value::Dict(..)) => Ok(()),
            (Some(target), _) => Err(format!(
                "BUILD of a {} with a {}: only a dict's attribute dict is expected",
                target.kind(),
                state.kind()
            )),
            (None, _) => Err("BUILD on an empty stack".into()),
        }
    }

    /// The operand of a memo opcode: one byte for BINPUT/BINGET, four for the LONG_ forms.
    fn memo_index(&mut self, op: u8) -> Result<u32, String> {
        match op {
            b'q' | b'h' => Ok(u32::from(self.byte()?)),
            _ => self.u32(),
        }
    }

    fn put(&mut self, index: u32) -> Result<(), String> {
        let top = match self.stack.last() {
            None => return Err("memo PUT on an empty stack".into()),
            Some(Value::Dict(..)) => None,
            Some(v) => Some(v.clone()),
        };
        self.memo.insert(index, top);
        Ok(())
    }

    fn get(&mut self, index: u32) -> Result<(), String> {
        match self.memo.get(&index) {
            None => Err(format!("memo GET {index} of nothing stored")),
            Some(None) => Err(format!(
                "memo GET {index} of a dict: shared mutable containers are not supported"
            )),
            Some(Some(v)) => {
                let v = v.clone();
                self.push(v)
            }
        }
    }

    fn push(&mut self, value: Value) -> Result<(), String> {
        self.stack.push(value);
        Ok(())
    }

    /// Pop one value, never below the innermost mark.
    #[expect(clippy::expect_used, reason = "pop_n(1) returns one value or an error")]
    fn pop(&mut self) -> Result<Value, String> {
        Ok(self.pop_n(1)?.pop().expect("one value"))
    }

    fn pop_n(&mut self, n: usize) -> Result<Vec<Value>, String> {
        let floor = self.marks.last().copied().unwrap_or(0);
        let above = self.stack.len() - floor;
        if above < n {
            return Err(format!(
                "{n} values needed, {above} on the stack above the mark"
            ));
        }
        Ok(self.stack.split_off(self.stack.len() - n))
    }

    fn pop_mark(&mut self) -> Result<Vec<Value>, String> {
        let mark = self.marks.pop().ok_or("no MARK to pop to")?;
        Ok(self.stack.split_off(mark))
    }

    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let left = self.bytes.len() - self.pos;
        if n > left {
            return Err(format!("truncated: {n} bytes needed, {left} left"));
        }
        let bytes = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(bytes)
    }

    fn byte(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    #[expect(clippy::expect_used, reason = "take(N) returns N bytes or an error")]
    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        Ok(self.take(N)?.try_into().expect("N bytes"))
    }

    fn u32(&mut self) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array()?))
    }

    /// A newline-terminated ASCII line (GLOBAL's operands).
    fn line(&mut self) -> Result<String, String> {
        let rest = &self.bytes[self.pos..];
        let len = rest
            .iter()
            .position(|&b| b == b'\n')
            .ok_or("truncated: GLOBAL operand without newline")?;
        let text = self.take(len + 1)?;
        match std::str::from_utf8(&text[..len]) {
            Ok(s) if s.is_ascii() => Ok(s.to_owned()),
            _ => Err("GLOBAL operand is not ASCII".into()),
        }
    }
}

/// BINPERSID's id: `('storage', torch.FloatStorage, key, location, numel)`.
fn persistent_storage(pid: &Value) -> Result<Storage, String> {
    let items: &[Value] = match pid {
        Value::Tuple(items, _) => items,
        other => return Err(format!("persistent id is a {}, not a tuple", other.kind())),
    };
    let [
        Value::Str(kind),
        Value::Global(Global::FloatStorage),
        Value::Str(key),
        Value::Str(_location),
        Value::Int(numel),
    ] = items
    else {
        return Err(format!(
            "persistent id ({}) is not ('storage', torch.FloatStorage, key, location, numel)",
            kinds(items)
        ));
    };
    if &**kind != "storage" {
        return Err(format!("persistent id of kind {kind:?}, not 'storage'"));
    }
    // The key becomes part of a zip entry name: keep it to the digits torch writes (and letters).
    if key.is_empty() || !key.bytes().all(|b| b.is_ascii_alphanumeric()) {
        return Err(format!("storage key {key:?} is not alphanumeric"));
    }
    let numel = u64::try_from(*numel).map_err(|_| format!("storage {key} of {numel} elements"))?;
    Ok(Storage {
        key: key.to_string(),
        numel,
    })
}

/// `_rebuild_tensor_v2(storage, offset, size, stride, requires_grad, backward_hooks[, metadata])`.
fn rebuild_tensor(args: &[Value]) -> Result<TensorRef, String> {
    let [
        Value::Storage(storage),
        Value::Int(offset),
        Value::Tuple(size, _),
        Value::Tuple(stride, _),
        Value::Bool(_),
        Value::Dict(hooks, _),
        rest @ ..,
    ] = args
    else {
        return Err(format!(
            "_rebuild_tensor_v2({}) is not (storage, offset, size, stride, requires_grad, \
             backward_hooks)",
            kinds(args)
        ));
    };
    if !hooks.is_empty() {
        return Err("_rebuild_tensor_v2 with backward hooks".into());
    }
    if !matches!(rest, [] | [Value::None] | [Value::Dict(..)]) {
        return Err(format!(
            "_rebuild_tensor_v2 extra arguments ({})",
            kinds(rest)
        ));
    }
    let offset = u64::try_from(*offset).map_err(|_| format!("storage offset {offset}"))?;
    Ok(TensorRef {
        storage: Rc::clone(storage),
        offset,
        size: dims(size, "size")?,
        stride: dims(stride, "stride")?,
    })
}

/// A size or stride tuple: at most `MAX_RANK` non-negative integers.
fn dims(values: &[Value], what: &str) -> Result<Vec<u64>, String> {
    if values.len() > MAX_RANK {
        return Err(format!("tensor {what} of {} dimensions", values.len()));
    }
    values
        .iter()
        .map(|v| match v {
            Value::Int(i) => u64::try_from(*i).map_err(|_| format!("tensor {what} entry {i}")),
            other => Err(format!("tensor {what} entry is a {}", other.kind())),
        })
        .collect()
}

fn kinds(values: &[Value]) -> String {
    if values.len() > 8 {
        return format!("{} values", values.len());
    }
    let kinds: Vec<String> = values.iter().map(Value::kind).collect();
    kinds.join(", ")
}
