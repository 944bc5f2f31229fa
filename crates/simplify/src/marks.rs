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
}
