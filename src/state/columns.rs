//! The `soa!` macro: declares a structure-of-arrays table once and derives from that single list
//! the owning struct (one `Vec` per column), a borrowed chunk type over a contiguous range of
//! environments (one `&mut [T]` per column) that splits in two without allocating, and the
//! per-column metadata (name, element kind, stride) used by hashing, memory accounting and,
//! later, the GPU buffers.
//!
//! Every column belongs to a *kind* (per environment, per human slot, ...): its stride is the
//! capacity of that kind, and element `slot` of environment `env` sits at `env * stride + slot`
//! (on the host; the GPU keeps another [`ElementOrder`], and `pack_in`/`unpack_in` convert).

/// Element type of a column, for hashing and GPU upload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Elem {
    /// 32-bit float.
    F32,
    /// 32-bit unsigned integer (ids, counts, flags: never `bool`, which WGSL cannot store).
    U32,
}

/// Where element `slot` of environment `e` sits in a state column of capacity `cap` on the
/// device, in a batch of `n` environments: at `e * cap + slot` (environment-major, the CPU's
/// order: one environment's slots together) or at `slot * n + e` (slot-major: one slot of
/// consecutive environments together, so that the lanes of a warp, consecutive environments,
/// touch consecutive words). The shaders never spell either: they index a kind's columns through
/// the prelude's `at_<kind>(e, slot)`, whose two steps, `e_<kind>` and `k_<kind>`, are
/// `crate::backend::wgsl::BatchLayout` values; the tables' `pack_in` and `unpack_in` convert.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ElementOrder {
    /// `e * cap + slot`.
    EnvMajor,
    /// `slot * n + e`.
    SlotMajor,
}

impl ElementOrder {
    /// The steps `(env_step, slot_step)` of a column of capacity `cap` in a batch of `n_envs`:
    /// element (e, slot) is at `e * env_step + slot * slot_step` from the column's first word.
    pub fn steps(self, n_envs: usize, cap: usize) -> (usize, usize) {
        match self {
            Self::EnvMajor => (cap, 1),
            Self::SlotMajor => (1, n_envs),
        }
    }
}

/// `dst` = `src` (same length), element by element when short: most columns of one environment
/// are a word or a few, where `copy_from_slice`'s call into `memcpy` costs more than the copy.
#[inline]
pub fn copy_words(dst: &mut [u32], src: &[u32]) {
    debug_assert_eq!(dst.len(), src.len(), "copy_words of unequal lengths");
    if src.len() <= 8 {
        for (d, s) in dst.iter_mut().zip(src) {
            *d = *s;
        }
    } else {
        dst.copy_from_slice(src);
    }
}

/// Set every element of `column` to its zero (the type's default), element by element when
/// short: most columns of one environment are a word or a few, or none (a capacity of 0), where
/// `fill`'s call into `memset` costs more than the stores. An empty column's pointer is a
/// dangling one, and glibc's AVX-512 `memset` writes even an empty range with one masked store,
/// whose suppressed fault on the unmapped page costs about 120 ns (45 times a short `memset`, on
/// the 2-vCPU machine): a fifth of a reset-pool row's time went there (`perf` over `pool_rows`).
#[inline]
pub fn zero<T: Copy + Default>(column: &mut [T]) {
    if column.len() <= 8 {
        for v in column {
            *v = T::default();
        }
    } else {
        column.fill(T::default());
    }
}

/// A value that can live in a column.
pub trait ColumnValue: Copy + Default + Send + Sync + 'static {
    /// Its element kind.
    const ELEM: Elem;
    /// Its bits, for fingerprints (`-0.0` is normalised to `+0.0`).
    fn bits(self) -> u32;
    /// The packed array of its element kind among the two (the GPU buffers hold every column of
    /// one kind back to back).
    fn packed<'a>(f32s: &'a mut Vec<f32>, u32s: &'a mut Vec<u32>) -> &'a mut Vec<Self>;
    /// [`ColumnValue::packed`], read only.
    fn packed_ref<'a>(f32s: &'a [f32], u32s: &'a [u32]) -> &'a [Self];
    /// `column` as its 32-bit words (an f32's bits), to be written in place.
    fn words_mut(column: &mut [Self]) -> &mut [u32];
    /// `column` as its 32-bit words, read only.
    fn words(column: &[Self]) -> &[u32];

    /// Append `column` (environment-major, `stride` elements per environment) to the packed
    /// array of its element kind in `order`.
    fn pack(
        column: &[Self],
        stride: usize,
        order: ElementOrder,
        f32s: &mut Vec<f32>,
        u32s: &mut Vec<u32>,
    ) {
        let out = Self::packed(f32s, u32s);
        match order {
            ElementOrder::SlotMajor if stride > 1 => {
                let n = column.len() / stride;
                out.extend(
                    (0..stride).flat_map(|slot| (0..n).map(move |e| column[e * stride + slot])),
                );
            }
            _ => out.extend_from_slice(column),
        }
    }

    /// The inverse of [`ColumnValue::pack`]: `column` read from the packed array of its kind at
    /// that array's cursor (moved past it).
    fn unpack(
        column: &mut [Self],
        stride: usize,
        order: ElementOrder,
        f32s: &[f32],
        u32s: &[u32],
        cursor: &mut [usize; 2],
    ) {
        let at = &mut cursor[usize::from(Self::ELEM == Elem::U32)];
        let words = &Self::packed_ref(f32s, u32s)[*at..*at + column.len()];
        match order {
            ElementOrder::SlotMajor if stride > 1 => {
                let n = column.len() / stride;
                for (k, &v) in words.iter().enumerate() {
                    column[(k % n) * stride + k / n] = v;
                }
            }
            _ => column.copy_from_slice(words),
        }
        *at += column.len();
    }
}

impl ColumnValue for f32 {
    const ELEM: Elem = Elem::F32;
    fn bits(self) -> u32 {
        if self == 0.0 { 0 } else { self.to_bits() }
    }
    fn packed<'a>(f32s: &'a mut Vec<f32>, _: &'a mut Vec<u32>) -> &'a mut Vec<Self> {
        f32s
    }
    fn packed_ref<'a>(f32s: &'a [f32], _: &'a [u32]) -> &'a [Self] {
        f32s
    }
    fn words_mut(column: &mut [Self]) -> &mut [u32] {
        bytemuck::cast_slice_mut(column)
    }
    fn words(column: &[Self]) -> &[u32] {
        bytemuck::cast_slice(column)
    }
}

impl ColumnValue for u32 {
    const ELEM: Elem = Elem::U32;
    fn bits(self) -> u32 {
        self
    }
    fn packed<'a>(_: &'a mut Vec<f32>, u32s: &'a mut Vec<u32>) -> &'a mut Vec<Self> {
        u32s
    }
    fn packed_ref<'a>(_: &'a [f32], u32s: &'a [u32]) -> &'a [Self] {
        u32s
    }
    fn words_mut(column: &mut [Self]) -> &mut [u32] {
        column
    }
    fn words(column: &[Self]) -> &[u32] {
        column
    }
}

/// Declare an SoA table: `soa! { pub struct Name / NameChunk over Strides { kind: col: T, ... } }`.
/// `Strides` must have a method `stride(&self, kind) -> usize` for each kind ident used.
macro_rules! soa {
    (
        $(#[$meta:meta])*
        pub struct $name:ident / $chunk:ident over $strides:ty {
            $( $(#[$cmeta:meta])* $kind:ident . $col:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone)]
        pub struct $name {
            /// Number of environments.
            pub n_envs: usize,
            /// Per-kind strides (capacities).
            pub strides: $strides,
            $( $(#[$cmeta])* pub $col: Vec<$ty>, )*
        }

        /// A mutable view of a contiguous range of environments of the table.
        #[derive(Debug)]
        pub struct $chunk<'a> {
            /// Number of environments in the chunk.
            pub n_envs: usize,
            /// Index of the chunk's first environment in the batch.
            pub first_env: usize,
            /// Per-kind strides (capacities).
            pub strides: $strides,
            $( $(#[$cmeta])* pub $col: &'a mut [$ty], )*
        }

        impl $name {
            /// A zero-filled table for `n_envs` environments.
            pub fn zeroed(n_envs: usize, strides: $strides) -> Self {
                Self {
                    n_envs,
                    $( $col: vec![<$ty>::default(); n_envs * strides.$kind()], )*
                    strides,
                }
            }

            /// The whole table as one chunk.
            pub fn chunk(&mut self) -> $chunk<'_> {
                $chunk {
                    n_envs: self.n_envs,
                    first_env: 0,
                    strides: self.strides,
                    $( $col: &mut self.$col[..], )*
                }
            }

            /// Environment `env` alone as a chunk.
            pub fn env_chunk(&mut self, env: usize) -> $chunk<'_> {
                let (_, rest) = self.chunk().split_at(env);
                rest.split_at(1).0
            }

            /// Every column's name and the kind of slot it is indexed by (`human`, `group`, ...:
            /// the ident before the dot in the declaration), in declaration order.
            pub const COLUMN_KINDS: &'static [(&'static str, &'static str)] =
                &[$( (stringify!($col), stringify!($kind)), )*];

            /// Column metadata: name, element kind, stride.
            pub fn columns(&self) -> Vec<(&'static str, $crate::state::columns::Elem, usize)> {
                vec![$( (
                    stringify!($col),
                    <$ty as $crate::state::columns::ColumnValue>::ELEM,
                    self.strides.$kind(),
                ), )*]
            }

            /// Every column appended to the packed array of its element kind, in declaration
            /// order (the layout of the GPU buffers; offsets from [`Self::columns`]), each
            /// column's elements environment-major.
            pub fn pack(&self, f32s: &mut Vec<f32>, u32s: &mut Vec<u32>) {
                self.pack_in($crate::state::columns::ElementOrder::EnvMajor, f32s, u32s);
            }

            /// [`Self::pack`] into `out` as 32-bit words (an f32's bits), the f32 array then the
            /// u32 array, without allocating: the reset pool's rows, one environment each, whose
            /// two hundred short columns made the growing vectors of [`Self::pack`] a sixth of a
            /// row's instructions. Returns the words written.
            pub fn pack_words(&self, out: &mut [u32]) -> usize {
                use $crate::state::columns::{ColumnValue, Elem, copy_words};
                let mut k = 0;
                // Two passes whose column tests are constants, so each compiles to its copies.
                $(
                    if <$ty as ColumnValue>::ELEM == Elem::F32 {
                        let words = <$ty as ColumnValue>::words(&self.$col);
                        copy_words(&mut out[k..k + words.len()], words);
                        k += words.len();
                    }
                )*
                $(
                    if <$ty as ColumnValue>::ELEM == Elem::U32 {
                        let words = <$ty as ColumnValue>::words(&self.$col);
                        copy_words(&mut out[k..k + words.len()], words);
                        k += words.len();
                    }
                )*
                k
            }

            /// [`Self::pack`] with each column's elements in `order`.
            pub fn pack_in(
                &self,
                order: $crate::state::columns::ElementOrder,
                f32s: &mut Vec<f32>,
                u32s: &mut Vec<u32>,
            ) {
                $( <$ty as $crate::state::columns::ColumnValue>::pack(
                    &self.$col, self.strides.$kind(), order, f32s, u32s,
                ); )*
            }

            /// The inverse of [`Self::pack`]: every column read back from the packed arrays.
            pub fn unpack(&mut self, f32s: &[f32], u32s: &[u32]) {
                self.unpack_in($crate::state::columns::ElementOrder::EnvMajor, f32s, u32s);
            }

            /// The inverse of [`Self::pack_in`].
            pub fn unpack_in(
                &mut self,
                order: $crate::state::columns::ElementOrder,
                f32s: &[f32],
                u32s: &[u32],
            ) {
                let mut cursor = [0usize; 2];
                $( <$ty as $crate::state::columns::ColumnValue>::unpack(
                    &mut self.$col, self.strides.$kind(), order, f32s, u32s, &mut cursor,
                ); )*
            }

            /// Column `name`'s 32-bit words (an f32 column's bits), to be written in place;
            /// `None` if the table has no such column.
            pub fn column_words_mut(&mut self, name: &str) -> Option<&mut [u32]> {
                $(
                    if name == stringify!($col) {
                        return Some(<$ty as $crate::state::columns::ColumnValue>::words_mut(&mut self.$col));
                    }
                )*
                None
            }

            /// Column `name`'s 32-bit words (an f32 column's bits); `None` if the table has no
            /// such column.
            pub fn column_words(&self, name: &str) -> Option<&[u32]> {
                $(
                    if name == stringify!($col) {
                        return Some(<$ty as $crate::state::columns::ColumnValue>::words(&self.$col));
                    }
                )*
                None
            }

            /// Names of the columns whose bits differ from `other`'s (same shape), for test
            /// failures that say where two states part.
            pub fn differing_columns(&self, other: &Self) -> Vec<&'static str> {
                let mut out = Vec::new();
                $(
                    let same = self.$col.len() == other.$col.len()
                        && self.$col.iter().zip(&other.$col).all(|(a, b)| {
                            <$ty as $crate::state::columns::ColumnValue>::bits(*a)
                                == <$ty as $crate::state::columns::ColumnValue>::bits(*b)
                        });
                    if !same {
                        out.push(stringify!($col));
                    }
                )*
                out
            }

            /// Bytes of state per environment (all columns).
            pub fn bytes_per_env(&self) -> usize {
                0 $( + self.strides.$kind() * std::mem::size_of::<$ty>() )*
            }

            /// FNV-1a hash over every column of environment `env`, in declaration order.
            pub fn fingerprint_env(&self, env: usize, mut h: u64) -> u64 {
                $(
                    let s = self.strides.$kind();
                    for v in &self.$col[env * s..(env + 1) * s] {
                        h = $crate::state::columns::fnv(h, <$ty as $crate::state::columns::ColumnValue>::bits(*v));
                    }
                )*
                h
            }

            /// Zero every per-slot column (all kinds but `env`) of environment `env`, so that
            /// the slots a new episode or a loaded document does not use hold zeros.
            pub fn clear_slots(&mut self, env: usize) {
                $(
                    if stringify!($kind) != "env" {
                        let s = self.strides.$kind();
                        $crate::state::columns::zero(&mut self.$col[env * s..(env + 1) * s]);
                    }
                )*
            }

            /// Copy every column of environment `from` of `src` into environment `to` of `self`.
            pub fn copy_env_from(&mut self, to: usize, src: &Self, from: usize) {
                $(
                    let s = self.strides.$kind();
                    self.$col[to * s..(to + 1) * s].copy_from_slice(&src.$col[from * s..(from + 1) * s]);
                )*
            }
        }

        impl<'a> $chunk<'a> {
            /// Reorder the first `used` slots of kind `kind` of local environment `env`: slot `k`
            /// receives the old slot `perm[k]`, in every column of that kind; slots from
            /// `perm.len()` to `used` (entries the permutation drops) are zeroed. Used by the social
            /// events, which regroup humans, groups and laptops (rare; at most [`MAX_PERMUTE`](crate::limits::MAX_PERMUTE)
            /// slots).
            pub fn permute(&mut self, kind: &str, env: usize, perm: &[u32], used: usize) {
                assert!(used <= $crate::limits::MAX_PERMUTE && perm.len() <= used, "permutation of {} of {used} slots", perm.len());
                $(
                    if stringify!($kind) == kind {
                        let s = self.strides.$kind();
                        let col = &mut self.$col[env * s..env * s + used];
                        let mut tmp = [<$ty>::default(); $crate::limits::MAX_PERMUTE];
                        for (k, &from) in perm.iter().enumerate() {
                            tmp[k] = col[from as usize];
                        }
                        col.copy_from_slice(&tmp[..used]);
                    }
                )*
            }

            /// Zero every per-slot column (all kinds but `env`) of local environment `env`.
            pub fn clear_slots(&mut self, env: usize) {
                $(
                    if stringify!($kind) != "env" {
                        let s = self.strides.$kind();
                        $crate::state::columns::zero(&mut self.$col[env * s..(env + 1) * s]);
                    }
                )*
            }

            /// Split into the first `mid` environments and the rest.
            pub fn split_at(self, mid: usize) -> ($chunk<'a>, $chunk<'a>) {
                assert!(mid <= self.n_envs, "split point {mid} beyond chunk of {} envs", self.n_envs);
                $( let $col = self.$col.split_at_mut(mid * self.strides.$kind()); )*
                (
                    $chunk {
                        n_envs: mid,
                        first_env: self.first_env,
                        strides: self.strides,
                        $( $col: $col.0, )*
                    },
                    $chunk {
                        n_envs: self.n_envs - mid,
                        first_env: self.first_env + mid,
                        strides: self.strides,
                        $( $col: $col.1, )*
                    },
                )
            }
        }
    };
}

pub(crate) use soa;

/// One FNV-1a round over a 32-bit word.
#[inline]
pub fn fnv(mut h: u64, word: u32) -> u64 {
    for byte in word.to_le_bytes() {
        h ^= u64::from(byte);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// FNV-1a offset basis.
pub const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
