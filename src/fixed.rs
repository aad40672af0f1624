//! `Fixed<T, N>`: a vector with its capacity on the stack, so code that runs inside a step (resets
//! included) never allocates. Exceeding the capacity is a broken internal invariant (capacities
//! are derived from the config) and panics with a message.

/// A stack-allocated vector of at most `N` items.
#[derive(Debug, Clone, Copy)]
pub struct Fixed<T: Copy + Default, const N: usize> {
    items: [T; N],
    len: usize,
}

impl<T: Copy + Default, const N: usize> Default for Fixed<T, N> {
    fn default() -> Self {
        Self {
            items: [T::default(); N],
            len: 0,
        }
    }
}

impl<T: Copy + Default, const N: usize> Fixed<T, N> {
    /// Append an item.
    #[inline]
    pub fn push(&mut self, item: T) {
        assert!(self.len < N, "fixed-capacity list of {N} items is full");
        self.items[self.len] = item;
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
    pub fn as_slice(&self) -> &[T] {
        &self.items[..self.len]
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
        self.items[..self.len][i] = item;
    }

    /// Shorten to `len` items.
    #[inline]
    pub fn truncate(&mut self, len: usize) {
        self.len = self.len.min(len);
    }
}

impl<T: Copy + Default, const N: usize> std::ops::Index<usize> for Fixed<T, N> {
    type Output = T;
    fn index(&self, i: usize) -> &T {
        &self.as_slice()[i]
    }
}
