//! Scratch marks: per-slot set membership without clearing or sorting. Each use takes a
//! fresh epoch; a slot is in the set of that epoch when its mark equals it, so marks of
//! earlier uses go stale for free.

/// One mark per vertex slot and the current epoch.
#[derive(Debug)]
pub(crate) struct ScratchMarks {
    marks: Vec<u32>,
    epoch: u32,
}

/// A set handed out by [`ScratchMarks::fresh`]: empty when taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Epoch(u32);

impl ScratchMarks {
    pub(crate) fn new(slots: usize) -> Self {
        Self { marks: vec![0; slots], epoch: 0 }
    }

    /// A new, empty set (every earlier set's marks become stale). On wrap-around the
    /// marks are cleared, so a stale mark can never equal a new epoch.
    #[inline]
    pub(crate) fn fresh(&mut self) -> Epoch {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.marks.fill(0);
            self.epoch = 1;
        }
        Epoch(self.epoch)
    }

    /// `len` new, consecutive values, the first returned: a slot holds value `base + i`
    /// when it was [`Self::set`] in this range, a value below `base` otherwise (every
    /// earlier set's and range's marks go stale). On wrap-around the marks are cleared.
    #[inline]
    pub(crate) fn fresh_range(&mut self, len: usize) -> u32 {
        let len = u32::try_from(len).expect("fewer than 2^32 values");
        if self.epoch.checked_add(len).is_none_or(|e| e == u32::MAX) {
            self.marks.fill(0);
            self.epoch = 0;
        }
        let base = self.epoch + 1;
        self.epoch += len;
        base
    }

    /// The value of `slot` (see [`Self::fresh_range`]).
    #[inline]
    pub(crate) fn get(&self, slot: u32) -> u32 {
        self.marks[slot as usize]
    }

    /// Gives `slot` the value `value` (see [`Self::fresh_range`]).
    #[inline]
    pub(crate) fn set(&mut self, slot: u32, value: u32) {
        self.marks[slot as usize] = value;
    }

    #[inline]
    pub(crate) fn insert(&mut self, slot: u32, set: Epoch) {
        self.marks[slot as usize] = set.0;
    }

    #[inline]
    pub(crate) fn contains(&self, slot: u32, set: Epoch) -> bool {
        self.marks[slot as usize] == set.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slot marked in one set is not in the next one, and a wrapped epoch clears.
    #[test]
    fn fresh_sets_start_empty() {
        let mut marks = ScratchMarks::new(3);
        let first = marks.fresh();
        marks.insert(1, first);
        assert!(marks.contains(1, first) && !marks.contains(0, first));
        let second = marks.fresh();
        assert!(!marks.contains(1, second));
        marks.epoch = u32::MAX;
        marks.insert(2, Epoch(u32::MAX));
        let wrapped = marks.fresh();
        assert_eq!(wrapped, Epoch(1));
        assert!(!marks.contains(2, wrapped) && !marks.contains(1, wrapped));
    }

    /// A range's values are at least its base; a later set's or range's base is above
    /// every value of the earlier ones, and a range that would wrap clears the marks.
    #[test]
    fn ranges_go_stale_like_sets() {
        let mut marks = ScratchMarks::new(3);
        let base = marks.fresh_range(10);
        marks.set(0, base + 9);
        assert!(marks.get(0) >= base && marks.get(1) < base);
        let set = marks.fresh();
        assert!(!marks.contains(0, set));
        let next = marks.fresh_range(5);
        assert!(marks.get(0) < next);
        marks.epoch = u32::MAX - 3;
        marks.set(2, u32::MAX - 3);
        let wrapped = marks.fresh_range(5);
        assert_eq!(wrapped, 1);
        assert!(marks.get(2) < wrapped);
    }
}
