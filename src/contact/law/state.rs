//! The state of every primary candidate of the loop, all pairs numbered one after another
//! (`crate::contact::iteration::solve`: pair `p`'s node `i` is `offsets[p] + i`): open, in contact,
//! and for Coulomb pairs, slipping (a node in contact and not slipping sticks). The partition is
//! what the loop's safeguard remembers and compares; the slipping nodes' directions are carried
//! beside it, as the gap linearization is.

use std::collections::BTreeSet;

#[derive(Debug, Clone, Default, PartialEq, Eq, Hash)]
pub struct NodeStates {
    /// The nodes in contact (the active set).
    pub contact: BTreeSet<usize>,
    /// The nodes in contact that slip (Coulomb pairs only; a subset of `contact`).
    pub slip: BTreeSet<usize>,
}

impl NodeStates {
    /// The states with `contact` in contact, none slipping.
    pub fn in_contact(contact: BTreeSet<usize>) -> Self {
        Self {
            contact,
            slip: BTreeSet::new(),
        }
    }

    /// The same partition with the contact set `contact`: a slipping node still in contact
    /// slips on, a node new in contact sticks.
    pub fn with_contact(&self, contact: BTreeSet<usize>) -> Self {
        let slip = self.slip.intersection(&contact).copied().collect();
        Self { contact, slip }
    }
}
