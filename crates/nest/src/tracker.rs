//! The collision tracker: the loss of every colliding pair of pieces and of every piece against
//! the static hazards (container exterior, defects, quality zones), with the guided-local-search
//! weights that grow on persistent collisions (Gardeyn & Vanden Berghe 2025, Alg. 8).
//!
//! Stored sparsely (each piece lists the pieces it collides with or carries a raised weight
//! for), so sheets and hides with many pieces cost memory in proportion to their collisions.

/// Weight growth on the worst collision of an iteration.
const WEIGHT_MAX_INC: f32 = 2.0;
/// Weight growth on the mildest collision.
const WEIGHT_MIN_INC: f32 = 1.2;
/// Weight decay back towards 1 while a pair does not collide.
const WEIGHT_DECAY: f32 = 0.95;

#[derive(Clone, Copy, Debug, PartialEq)]
struct Entry {
    loss: f32,
    weight: f32,
}

impl Entry {
    const CLEAR: Self = Self {
        loss: 0.0,
        weight: 1.0,
    };
    fn weighted(&self) -> f32 {
        self.loss * self.weight
    }
    fn idle(&self) -> bool {
        self.loss == 0.0 && self.weight <= 1.0
    }
    fn grow(&mut self, max_loss: f32) {
        let m = if self.loss == 0.0 {
            WEIGHT_DECAY
        } else {
            WEIGHT_MIN_INC + (WEIGHT_MAX_INC - WEIGHT_MIN_INC) * (self.loss / max_loss)
        };
        self.weight = (self.weight * m).max(1.0);
    }
}

/// Losses and weights of the pieces of one layout, indexed by piece instance.
#[derive(Clone, Debug)]
pub(crate) struct Tracker {
    /// Per instance: (other instance, entry); every pair is listed on both sides.
    pairs: Vec<Vec<(u32, Entry)>>,
    /// Per instance: exterior, defects and zones together.
    stat: Vec<Entry>,
}

/// The losses of a tracker (without weights), to roll back to.
#[derive(Clone, Debug, Default)]
pub(crate) struct Losses {
    pairs: Vec<(u32, u32, f32)>,
    stat: Vec<(u32, f32)>,
}

impl Tracker {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            pairs: vec![Vec::new(); n],
            stat: vec![Entry::CLEAR; n],
        }
    }

    fn slot(&mut self, i: usize, j: u32) -> &mut Entry {
        let list = &mut self.pairs[i];
        match list.iter().position(|(k, _)| *k == j) {
            Some(p) => &mut list[p].1,
            None => {
                list.push((j, Entry::CLEAR));
                &mut list.last_mut().expect("just pushed").1
            }
        }
    }

    pub(crate) fn pair_weight(&self, i: usize, j: usize) -> f32 {
        self.pairs[i]
            .iter()
            .find(|(k, _)| *k as usize == j)
            .map_or(1.0, |(_, e)| e.weight)
    }

    pub(crate) fn static_weight(&self, i: usize) -> f32 {
        self.stat[i].weight
    }

    /// Replaces the losses of instance `i`: `hits` are (other instance, loss) pairs.
    pub(crate) fn set_losses(&mut self, i: usize, hits: &[(u32, f32)], stat_loss: f32) {
        let old: Vec<u32> = self.pairs[i].iter().map(|(k, _)| *k).collect();
        for j in old {
            self.slot(i, j).loss = 0.0;
            self.slot(j as usize, i as u32).loss = 0.0;
        }
        for &(j, l) in hits {
            self.slot(i, j).loss = l;
            self.slot(j as usize, i as u32).loss = l;
        }
        self.stat[i].loss = stat_loss;
    }

    /// Unweighted loss of instance `i`.
    pub(crate) fn loss(&self, i: usize) -> f32 {
        self.stat[i].loss + self.pairs[i].iter().map(|(_, e)| e.loss).sum::<f32>()
    }

    pub(crate) fn total_loss(&self) -> f32 {
        let mut t = 0.0;
        for (i, list) in self.pairs.iter().enumerate() {
            t += self.stat[i].loss;
            t += list
                .iter()
                .filter(|(j, _)| *j as usize > i)
                .map(|(_, e)| e.loss)
                .sum::<f32>();
        }
        t
    }

    pub(crate) fn total_weighted_loss(&self) -> f32 {
        let mut t = 0.0;
        for (i, list) in self.pairs.iter().enumerate() {
            t += self.stat[i].weighted();
            t += list
                .iter()
                .filter(|(j, _)| *j as usize > i)
                .map(|(_, e)| e.weighted())
                .sum::<f32>();
        }
        t
    }

    /// Raises the weights of colliding pairs in proportion to their loss and lets the others
    /// decay (Alg. 8); drops pairs back at rest.
    pub(crate) fn update_weights(&mut self) {
        let max_loss = self
            .stat
            .iter()
            .map(|e| e.loss)
            .chain(self.pairs.iter().flatten().map(|(_, e)| e.loss))
            .fold(0.0f32, f32::max);
        for e in &mut self.stat {
            e.grow(max_loss);
        }
        for list in &mut self.pairs {
            for (_, e) in list.iter_mut() {
                e.grow(max_loss);
            }
            list.retain(|(_, e)| !e.idle());
        }
    }

    /// The current losses, to restore later with [`Self::restore_losses`].
    pub(crate) fn losses(&self) -> Losses {
        let mut out = Losses::default();
        for (i, list) in self.pairs.iter().enumerate() {
            for (j, e) in list {
                if *j as usize > i && e.loss > 0.0 {
                    out.pairs.push((i as u32, *j, e.loss));
                }
            }
            if self.stat[i].loss > 0.0 {
                out.stat.push((i as u32, self.stat[i].loss));
            }
        }
        out
    }

    /// Restores saved losses, keeping the current weights.
    pub(crate) fn restore_losses(&mut self, l: &Losses) {
        for list in &mut self.pairs {
            for (_, e) in list.iter_mut() {
                e.loss = 0.0;
            }
        }
        for e in &mut self.stat {
            e.loss = 0.0;
        }
        for &(i, j, loss) in &l.pairs {
            self.slot(i as usize, j).loss = loss;
            self.slot(j as usize, i).loss = loss;
        }
        for &(i, loss) in &l.stat {
            self.stat[i as usize].loss = loss;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn losses_are_symmetric_and_weights_grow_on_collisions() {
        let mut t = Tracker::new(3);
        t.set_losses(0, &[(1, 2.0)], 0.5);
        assert_eq!(t.loss(1), 2.0);
        assert_eq!(t.loss(0), 2.5);
        assert_eq!(t.total_loss(), 2.5);
        t.update_weights();
        // the worst collision doubles, the exterior one grows by 1.2 + 0.8 * 0.25
        assert!((t.pair_weight(0, 1) - 2.0).abs() < 1e-6);
        assert!((t.pair_weight(1, 0) - 2.0).abs() < 1e-6);
        assert!((t.static_weight(0) - 1.4).abs() < 1e-6);
        assert!((t.total_weighted_loss() - (4.0 + 0.7)).abs() < 1e-5);
        let saved = t.losses();
        t.set_losses(0, &[(2, 1.0)], 0.0);
        assert_eq!(t.loss(1), 0.0);
        assert_eq!(t.loss(2), 1.0);
        t.restore_losses(&saved);
        assert_eq!(t.loss(1), 2.0);
        assert_eq!(t.loss(2), 0.0);
        // without collisions the weights decay back to 1 and the pair is dropped
        t.set_losses(0, &[], 0.0);
        for _ in 0..40 {
            t.update_weights();
        }
        assert_eq!(t.pair_weight(0, 1), 1.0);
        assert!(t.pairs[0].is_empty());
    }
}
