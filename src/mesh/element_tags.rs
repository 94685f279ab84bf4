//! The gmsh element tags of a body's cells, kept as runs of consecutive tags where they
//! follow one another.
//!
//! gmsh numbers the elements of a block one after the other, so a body's cells (in the file's
//! order) carry a few runs `t, t + 1, t + 2, ...`: kept as runs, the tags take 16 bytes a run
//! instead of 8 a cell (16 MB at 1M DOFs, on every rank of a distributed run). Tags in any
//! other order are kept one by one, so no file costs more than 8 bytes a cell.

use serde::{Deserialize, Serialize};

/// The tag of each cell of a body, in cell order.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ElementTags {
    len: usize,
    storage: Storage,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
enum Storage {
    /// `(first cell, its tag)` of each run, first cells increasing from 0: run `r` holds the
    /// cells up to the next run's first, tags increasing by one.
    Runs(Vec<(usize, u64)>),
    /// One tag a cell.
    Each(Vec<u64>),
}

impl ElementTags {
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The tag of cell `c`.
    ///
    /// # Panics
    /// If `c` is not below [`Self::len`], as a slice's index would.
    pub fn get(&self, c: usize) -> u64 {
        assert!(c < self.len, "cell {c} of {} cells", self.len);
        match &self.storage {
            Storage::Each(tags) => tags[c],
            Storage::Runs(runs) => {
                let r = runs.partition_point(|&(first, _)| first <= c) - 1;
                let (first, tag) = runs[r];
                tag + (c - first) as u64
            }
        }
    }

    /// The tags in cell order.
    pub fn iter(&self) -> impl Iterator<Item = u64> + '_ {
        (0..self.len).scan(0, move |run, c| match &self.storage {
            Storage::Each(tags) => Some(tags[c]),
            Storage::Runs(runs) => {
                while *run + 1 < runs.len() && runs[*run + 1].0 <= c {
                    *run += 1;
                }
                let (first, tag) = runs[*run];
                Some(tag + (c - first) as u64)
            }
        })
    }

    pub fn to_vec(&self) -> Vec<u64> {
        self.iter().collect()
    }
}

impl From<Vec<u64>> for ElementTags {
    /// Runs where they take less room than the tags themselves (a run takes two tags' room).
    fn from(tags: Vec<u64>) -> Self {
        let mut runs: Vec<(usize, u64)> = Vec::new();
        for (c, &tag) in tags.iter().enumerate() {
            let follows = c > 0 && tags[c - 1].checked_add(1) == Some(tag);
            if !follows {
                runs.push((c, tag));
                if 2 * runs.len() > tags.len() {
                    break;
                }
            }
        }
        let len = tags.len();
        let storage = match 2 * runs.len() <= len {
            true => Storage::Runs(runs),
            false => Storage::Each(tags),
        };
        Self { len, storage }
    }
}

impl FromIterator<u64> for ElementTags {
    fn from_iter<I: IntoIterator<Item = u64>>(tags: I) -> Self {
        Self::from(tags.into_iter().collect::<Vec<_>>())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn consecutive_tags_are_runs_and_read_back_whole() {
        let tags: Vec<u64> = (10..15).chain(100..103).chain([7, 8]).collect();
        let kept = ElementTags::from(tags.clone());
        assert!(matches!(&kept.storage, Storage::Runs(runs) if runs.len() == 3));
        assert_eq!(kept.to_vec(), tags);
        assert_eq!(kept.len(), tags.len());
        for (c, &tag) in tags.iter().enumerate() {
            assert_eq!(kept.get(c), tag, "cell {c}");
        }
    }

    #[test]
    fn tags_that_rarely_follow_one_another_are_kept_one_by_one() {
        let tags = vec![5, 3, 9, 10, 2, 8, u64::MAX, 0];
        let kept = ElementTags::from(tags.clone());
        assert!(matches!(kept.storage, Storage::Each(_)));
        assert_eq!(kept.to_vec(), tags);
        assert_eq!(kept.get(6), u64::MAX);
    }

    #[test]
    fn no_tags() {
        let kept = ElementTags::from(Vec::new());
        assert!(kept.is_empty());
        assert_eq!(kept.iter().count(), 0);
    }

    #[test]
    #[should_panic(expected = "cell 3 of 3 cells")]
    fn a_cell_past_the_end_panics_as_a_slice_would() {
        ElementTags::from(vec![1, 2, 3]).get(3);
    }
}
