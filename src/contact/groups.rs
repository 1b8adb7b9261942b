//! Independent groups of a contact projection: the members (islands and loose particles)
//! that contact rows join, directly or through other members. Groups share no particle
//! and no row, so each is projected on its own — to its own number of Newton steps and
//! sweeps, where one projection of everything would iterate every group until the
//! hardest is met.

use crate::model::union_find::UnionFind;

/// A row's members (slots), `NONE` where a particle belongs to no member.
pub type RowSlots = [u32; 3];

/// No member.
pub const NONE: u32 = u32::MAX;

/// The groups of the last [`ContactGroups::partition`].
#[derive(Clone, Debug, Default)]
pub struct ContactGroups {
    sets: UnionFind,
    /// Each slot's group.
    pub slot_group: Vec<u32>,
    /// Each row's group, `NONE` for a row that touches no member.
    pub row_group: Vec<u32>,
    /// Groups found, numbered in the order of their smallest slot.
    pub count: usize,
    /// Slots, then rows, bucketed by group (each bucket in index order), and where
    /// each group's bucket starts (`count + 1` entries).
    slot_order: Vec<u32>,
    slot_start: Vec<u32>,
    row_order: Vec<u32>,
    row_start: Vec<u32>,
    cursor: Vec<u32>,
}

impl ContactGroups {
    /// Group `slots` members joined by `rows`.
    pub fn partition(&mut self, slots: usize, rows: &[RowSlots]) {
        self.sets.reset(slots);
        for row in rows {
            let members = row.iter().filter(|&&s| s != NONE).map(|&s| s as usize);
            self.sets.union_all(members);
        }
        // A set is named by its smallest slot, so numbering roots in slot order gives
        // the same numbers whatever the order of the rows.
        self.slot_group.clear();
        self.slot_group.resize(slots, NONE);
        self.count = 0;
        for slot in 0..slots {
            let root = self.sets.find(slot);
            if root == slot {
                self.slot_group[slot] = self.count as u32;
                self.count += 1;
            } else {
                self.slot_group[slot] = self.slot_group[root];
            }
        }
        self.row_group.clear();
        self.row_group.extend(rows.iter().map(|row| {
            (row.iter())
                .find(|&&s| s != NONE)
                .map_or(NONE, |&s| self.slot_group[s as usize])
        }));
        let cursor = &mut self.cursor;
        bucket(
            &self.slot_group,
            self.count,
            &mut self.slot_order,
            &mut self.slot_start,
            cursor,
        );
        bucket(
            &self.row_group,
            self.count,
            &mut self.row_order,
            &mut self.row_start,
            cursor,
        );
    }

    /// The slots of group `g`, ascending.
    pub fn slots_of(&self, g: u32) -> &[u32] {
        let g = g as usize;
        &self.slot_order[self.slot_start[g] as usize..self.slot_start[g + 1] as usize]
    }

    /// The rows of group `g`, ascending.
    pub fn rows_of(&self, g: u32) -> &[u32] {
        let g = g as usize;
        &self.row_order[self.row_start[g] as usize..self.row_start[g + 1] as usize]
    }
}

/// Indices of `group` bucketed by group (a counting sort, so each bucket keeps index
/// order; `NONE` left out) and the buckets' starts; `cursor` is scratch.
fn bucket(
    group: &[u32],
    count: usize,
    order: &mut Vec<u32>,
    start: &mut Vec<u32>,
    cursor: &mut Vec<u32>,
) {
    start.clear();
    start.resize(count + 1, 0);
    for &g in group.iter().filter(|&&g| g != NONE) {
        start[g as usize + 1] += 1;
    }
    for g in 0..count {
        start[g + 1] += start[g];
    }
    order.clear();
    order.resize(start[count] as usize, 0);
    cursor.clear();
    cursor.extend_from_slice(start);
    for (i, &g) in group.iter().enumerate().filter(|&(_, &g)| g != NONE) {
        order[cursor[g as usize] as usize] = i as u32;
        cursor[g as usize] += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Groups by brute force: repeatedly merge labels along rows until nothing changes.
    fn brute_force(slots: usize, rows: &[RowSlots]) -> Vec<usize> {
        let mut label: Vec<usize> = (0..slots).collect();
        loop {
            let mut changed = false;
            for row in rows {
                let members: Vec<usize> = (row.iter())
                    .filter(|&&s| s != NONE)
                    .map(|&s| s as usize)
                    .collect();
                let least = members.iter().map(|&m| label[m]).min();
                for &m in &members {
                    if let Some(least) = least
                        && label[m] != least
                    {
                        label[m] = least;
                        changed = true;
                    }
                }
            }
            if !changed {
                return label;
            }
        }
    }

    #[test]
    fn groups_are_the_connected_members_numbered_in_slot_order() {
        let rows = [
            [3, 5, NONE],
            [NONE, NONE, NONE],
            [7, 7, 1],
            [5, NONE, 8],
            [0, NONE, NONE],
        ];
        let mut groups = ContactGroups::default();
        groups.partition(9, &rows);
        // {0}, {1, 7}, {2}, {3, 5, 8}, {4}, {6}
        assert_eq!(groups.count, 6);
        assert_eq!(groups.slot_group, vec![0, 1, 2, 3, 4, 3, 5, 1, 3]);
        assert_eq!(groups.row_group, vec![3, NONE, 1, 3, 0]);
        assert_eq!(groups.slots_of(3), &[3, 5, 8]);
        assert_eq!(groups.slots_of(1), &[1, 7]);
        assert_eq!(groups.rows_of(3), &[0, 3]);
        assert_eq!(groups.rows_of(5), &[] as &[u32]);
    }

    #[test]
    fn groups_match_a_brute_force_labelling_and_ignore_row_order() {
        // A deterministic scramble of rows over 60 slots.
        let mut seed = 12345u64;
        let mut next = |n: u64| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) % n) as u32
        };
        let rows: Vec<RowSlots> = (0..45)
            .map(|_| {
                let mut row = [next(60), next(60), NONE];
                if next(3) == 0 {
                    row[2] = next(60);
                }
                if next(5) == 0 {
                    row[0] = NONE;
                }
                row
            })
            .collect();
        let mut groups = ContactGroups::default();
        groups.partition(60, &rows);
        let labels = brute_force(60, &rows);
        for a in 0..60 {
            for b in 0..60 {
                assert_eq!(
                    groups.slot_group[a] == groups.slot_group[b],
                    labels[a] == labels[b],
                    "slots {a} and {b}"
                );
            }
        }
        let mut reversed = rows.clone();
        reversed.reverse();
        let mut again = ContactGroups::default();
        again.partition(60, &reversed);
        assert_eq!(again.slot_group, groups.slot_group);
    }
}
