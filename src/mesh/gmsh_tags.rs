//! The gmsh tags of a body's nodes or cells, kept as runs of consecutive tags where they
//! follow one another.
//!
//! gmsh numbers the nodes of a geometric entity, and the elements of a block, one after the
//! other, so a body's cells (in the file's order) carry a few runs `t, t + 1, t + 2, ...`, and
//! so do its nodes in increasing tag order (four runs a body in the demo's meshes: the
//! entities' nodes). Kept as runs, the tags take 16 bytes a run instead of 8 a node or cell
//! (16 MB of cell tags at 1M DOFs; the node tags are kept by every rank of a distributed run).
//! Tags in any other order are kept one by one, so no file costs more than 8 bytes a tag.

use serde::{Deserialize, Serialize};

/// The tag of each node or cell of a body, in the body's order.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct GmshTags {
    len: usize,
    storage: Storage,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
enum Storage {
    /// `(first index, its tag)` of each run, first indices increasing from 0: run `r` holds
    /// the indices up to the next run's first, tags increasing by one.
    Runs(Vec<(usize, u64)>),
    /// One tag an index.
    Each(Vec<u64>),
}

impl GmshTags {
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The tag at index `c`.
    ///
    /// # Panics
    /// If `c` is not below [`Self::len`], as a slice's index would.
    pub fn get(&self, c: usize) -> u64 {
        assert!(c < self.len, "index {c} of {} tags", self.len);
        match &self.storage {
            Storage::Each(tags) => tags[c],
            Storage::Runs(runs) => {
                let r = runs.partition_point(|&(first, _)| first <= c) - 1;
                let (first, tag) = runs[r];
                tag + (c - first) as u64
            }
        }
    }

    /// The index of `tag`, where the tags increase (a body's node tags,
    /// [`super::BodyMesh::node_tags`]); `None` if it is not one of them.
    pub fn position(&self, tag: u64) -> Option<usize> {
        match &self.storage {
            Storage::Each(tags) => tags.binary_search(&tag).ok(),
            Storage::Runs(runs) => {
                let r = runs.partition_point(|&(_, first_tag)| first_tag <= tag);
                let (first, first_tag) = *runs.get(r.checked_sub(1)?)?;
                let end = runs.get(r).map_or(self.len, |&(next, _)| next);
                let c = first.checked_add(usize::try_from(tag - first_tag).ok()?)?;
                (c < end).then_some(c)
            }
        }
    }

    /// The tags in order.
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

impl From<Vec<u64>> for GmshTags {
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

impl FromIterator<u64> for GmshTags {
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
        let kept = GmshTags::from(tags.clone());
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
        let kept = GmshTags::from(tags.clone());
        assert!(matches!(kept.storage, Storage::Each(_)));
        assert_eq!(kept.to_vec(), tags);
        assert_eq!(kept.get(6), u64::MAX);
    }

    #[test]
    fn an_increasing_tag_is_found_where_it_is_and_a_missing_one_nowhere() {
        let increasing: Vec<u64> = (3..9).chain(20..30).chain([31, 40, 41]).collect();
        let by_runs = GmshTags::from(increasing.clone());
        assert!(matches!(&by_runs.storage, Storage::Runs(runs) if runs.len() == 4));
        let each = GmshTags::from(vec![2, 5, 9, 11, 17]);
        assert!(matches!(each.storage, Storage::Each(_)));
        for kept in [&by_runs, &each] {
            let tags = kept.to_vec();
            for (c, &tag) in tags.iter().enumerate() {
                assert_eq!(kept.position(tag), Some(c), "tag {tag}");
            }
            for missing in [0, 1, 10, 19, 30, 32, 39, 42, u64::MAX - 3, u64::MAX] {
                assert_eq!(kept.position(missing), None, "tag {missing}");
            }
        }
    }

    #[test]
    fn no_tags() {
        let kept = GmshTags::from(Vec::new());
        assert!(kept.is_empty());
        assert_eq!(kept.iter().count(), 0);
    }

    #[test]
    #[should_panic(expected = "index 3 of 3 tags")]
    fn a_cell_past_the_end_panics_as_a_slice_would() {
        GmshTags::from(vec![1, 2, 3]).get(3);
    }
}
