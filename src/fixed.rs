//! `Fixed<T, N>`: a vector with its capacity on the stack, so code that runs inside a step (resets
//! included) never allocates. Exceeding the capacity is a broken internal invariant (capacities
//! are derived from the config) and panics with a message.

use std::mem::MaybeUninit;

/// A stack-allocated vector of at most `N` items.
///
/// The items past `len` are left uninitialised: a new list writes nothing, and moving one copies
/// nothing the compiler must keep. Lists sized for every config are large (a scenario's spawn
/// list is about 22 KB), and zeroing and then moving each new one was a fifth of the
/// instructions of a reset-pool row (a reset and its first observation).
#[derive(Clone, Copy)]
pub struct Fixed<T: Copy, const N: usize> {
    /// Invariant: `items[..len]` are initialised (written by `push`, moved by `remove`).
    items: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Default for Fixed<T, N> {
    fn default() -> Self {
        Self {
            items: [const { MaybeUninit::uninit() }; N],
            len: 0,
        }
    }
}

impl<T: Copy + std::fmt::Debug, const N: usize> std::fmt::Debug for Fixed<T, N> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

impl<T: Copy, const N: usize> Fixed<T, N> {
    /// Append an item.
    #[inline]
    pub fn push(&mut self, item: T) {
        assert!(self.len < N, "fixed-capacity list of {N} items is full");
        self.items[self.len] = MaybeUninit::new(item);
        self.len += 1;
    }

    /// Remove every item.
    #[inline]
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Number of items.
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when empty.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The items.
    #[inline]
    #[expect(
        unsafe_code,
        reason = "reads the initialised prefix of a MaybeUninit array as items; sound, see below"
    )]
    pub fn as_slice(&self) -> &[T] {
        let items = &self.items[..self.len];
        // SAFETY: `items[..len]` are initialised (the type's invariant), and `MaybeUninit<T>` has
        // `T`'s size, alignment and layout, so the prefix is a valid `[T]` for its lifetime.
        unsafe { std::slice::from_raw_parts(items.as_ptr().cast::<T>(), items.len()) }
    }

    /// Remove item `i`, shifting the later ones down (order kept).
    #[inline]
    pub fn remove(&mut self, i: usize) -> T {
        let item = self.as_slice()[i];
        self.items.copy_within(i + 1..self.len, i);
        self.len -= 1;
        item
    }

    /// Exchange items `i` and `j`.
    #[inline]
    pub fn swap(&mut self, i: usize, j: usize) {
        self.items[..self.len].swap(i, j);
    }

    /// Replace item `i`.
    #[inline]
    pub fn set(&mut self, i: usize, item: T) {
        self.items[..self.len][i] = MaybeUninit::new(item);
    }

    /// Shorten to `len` items.
    #[inline]
    pub fn truncate(&mut self, len: usize) {
        self.len = self.len.min(len);
    }
}

impl<T: Copy, const N: usize> std::ops::Index<usize> for Fixed<T, N> {
    type Output = T;
    fn index(&self, i: usize) -> &T {
        &self.as_slice()[i]
    }
}

#[cfg(test)]
mod tests {
    use super::Fixed;

    /// Contract: the list reads back what was pushed, in order, through every edit, and a new
    /// list (whose items are uninitialised) reads as empty.
    #[test]
    fn edits_keep_the_items_in_order() {
        let mut f: Fixed<(u8, f32), 6> = Fixed::default();
        assert!(f.is_empty() && f.as_slice().is_empty());
        for k in 0..5u8 {
            f.push((k, f32::from(k) * 0.5));
        }
        assert_eq!(f.len(), 5);
        assert_eq!(f.remove(1), (1, 0.5));
        assert_eq!(f.as_slice(), &[(0, 0.0), (2, 1.0), (3, 1.5), (4, 2.0)]);
        f.swap(0, 3);
        f.set(1, (9, 9.0));
        assert_eq!(f.as_slice(), &[(4, 2.0), (9, 9.0), (3, 1.5), (0, 0.0)]);
        assert_eq!(f[2], (3, 1.5));
        let copy = f;
        f.truncate(2);
        f.push((7, 7.0));
        assert_eq!(f.as_slice(), &[(4, 2.0), (9, 9.0), (7, 7.0)]);
        assert_eq!(copy.len(), 4, "a copy keeps its own items");
        assert_eq!(format!("{f:?}"), "[(4, 2.0), (9, 9.0), (7, 7.0)]");
        f.clear();
        assert!(f.as_slice().is_empty());
    }

    /// Contract: pushing past the capacity is a broken invariant, which panics naming it.
    #[test]
    #[should_panic(expected = "fixed-capacity list of 2 items is full")]
    fn pushing_past_the_capacity_panics() {
        let mut f: Fixed<u32, 2> = Fixed::default();
        for k in 0..3 {
            f.push(k);
        }
    }
}
