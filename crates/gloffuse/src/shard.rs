//! Splitting one run into shards that farm nodes run apart (`--shard K/N`), and checking a
//! set of shard reports before they are merged. The split is a pure function of the items'
//! estimated costs, so every node, given the same inputs, computes the same split and takes
//! its own part: no queue, no coordinator.

use std::path::PathBuf;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::{Error, Field, Hint};

/// Shard `index` of `count`, counted from 1 as `--shard K/N` writes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl FromStr for Shard {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        let bad = || Error::input(Field::Shard, s, "K/N with 1 ≤ K ≤ N, e.g. 2/3");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            k.trim().parse::<usize>().map_err(|_| bad())?,
            n.trim().parse::<usize>().map_err(|_| bad())?,
        );
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Whether this shard runs each item, given every item's cost (see [`assign`]).
    pub fn takes(self, costs: &[u64]) -> Vec<bool> {
        assign(costs, self.count)
            .into_iter()
            .map(|s| s + 1 == self.index)
            .collect()
    }
}

/// The shard (from 0) that runs each item: the costliest item first, each to the shard with
/// the least cost so far (ties: the lower shard, then the earlier item) — Graham's
/// longest-processing-time rule, whose longest shard is within 4/3 of the best split.
pub fn assign(costs: &[u64], count: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..costs.len()).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(costs[i]), i));
    let mut load = vec![0u64; count.max(1)];
    let mut shard_of = vec![0; costs.len()];
    for i in order {
        let lightest = (0..load.len())
            .min_by_key(|&s| (load[s], s))
            .expect("at least one shard");
        load[lightest] += costs[i];
        shard_of[i] = lightest;
    }
    shard_of
}

/// Puts shard reports in shard order, each checked against the first: every shard of the
/// same count given exactly once. `shards` holds each report's path and its shard (`None`:
/// a report made without `--shard`).
pub fn in_order<T>(shards: Vec<(PathBuf, Option<Shard>, T)>) -> Result<Vec<(PathBuf, T)>, Error> {
    let Some(count) = shards.first().and_then(|(_, s, _)| *s).map(|s| s.count) else {
        let path = shards.first().map(|(p, _, _)| p.display().to_string());
        return Err(Error::input(
            Field::ShardReport,
            path.unwrap_or_default(),
            Hint::new(
                "a shard's report (made by a run with {} K/N)",
                [Field::Shard],
            ),
        ));
    };
    let mut slots: Vec<Option<(PathBuf, T)>> = (0..count).map(|_| None).collect();
    for (path, shard, report) in shards {
        let Some(shard) = shard.filter(|s| s.count == count) else {
            let what = match shard {
                Some(s) => Hint::text(format!("shard {s}")),
                None => Hint::new("a report made without {}", [Field::Shard]),
            };
            return Err(Error::input(
                Field::ShardReport,
                path.display(),
                Hint::text(format!("a shard of {count} like the first report, not ")).then(what),
            ));
        };
        let slot = &mut slots[shard.index - 1];
        if let Some((first, _)) = slot {
            return Err(Error::input(
                Field::ShardReport,
                path.display(),
                Hint::text(format!(
                    "each shard once: shard {shard} is also {}",
                    first.display()
                )),
            ));
        }
        *slot = Some((path, report));
    }
    let missing: Vec<String> = (1..=count)
        .filter(|&k| slots[k - 1].is_none())
        .map(|k| format!("{k}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(Error::input(
            Field::ShardReport,
            format!("{} reports", count - missing.len()),
            Hint::new(
                format!(
                    "every shard of {count}: missing {} (its report.json or {{}} folder)",
                    missing.join(", ")
                ),
                [Field::Report],
            ),
        ));
    }
    Ok(slots.into_iter().map(|s| s.expect("checked")).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_k_of_n_and_refuses_the_rest() {
        assert_eq!(
            "2/3".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 3 }
        );
        for bad in ["0/3", "4/3", "3", "a/b", "1/0", "-1/2", ""] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    #[test]
    fn every_item_goes_to_one_shard_and_the_loads_are_balanced() {
        let costs: Vec<u64> = (0..50).map(|i| (i * 37 % 11) + 1).collect();
        for n in 1..=7 {
            let shard_of = assign(&costs, n);
            let mut load = vec![0u64; n];
            for (i, &s) in shard_of.iter().enumerate() {
                load[s] += costs[i];
            }
            let total: u64 = costs.iter().sum();
            let biggest = *costs.iter().max().unwrap();
            // LPT's bound: no shard exceeds the mean by more than the costliest item.
            let max = *load.iter().max().unwrap();
            assert!(max <= total.div_ceil(n as u64) + biggest, "{n}: {load:?}");
            // Takes partitions the items: each in exactly one shard.
            let takes: Vec<Vec<bool>> = (1..=n)
                .map(|k| Shard { index: k, count: n }.takes(&costs))
                .collect();
            for i in 0..costs.len() {
                assert_eq!(takes.iter().filter(|t| t[i]).count(), 1);
            }
        }
    }

    #[test]
    fn the_split_is_the_known_one() {
        // Worked by hand: 9 → shard 0; 7 → 1; 5 → 2; 4 → 2 (5 < 7 < 9); 1, 1 → 1, 1.
        assert_eq!(assign(&[4, 9, 1, 7, 5, 1], 3), vec![2, 0, 1, 1, 2, 1]);
    }

    fn shard(k: usize, n: usize) -> Option<Shard> {
        Some(Shard { index: k, count: n })
    }

    #[test]
    fn a_set_of_shards_is_whole_and_each_once() {
        let p = |s: &str| PathBuf::from(s);
        let ok = in_order(vec![(p("b"), shard(2, 2), 'b'), (p("a"), shard(1, 2), 'a')]).unwrap();
        assert_eq!(ok, vec![(p("a"), 'a'), (p("b"), 'b')]);
        let twice = in_order(vec![(p("a"), shard(1, 2), 0), (p("c"), shard(1, 2), 0)]);
        assert!(
            twice
                .unwrap_err()
                .to_string()
                .contains("shard 1/2 is also a")
        );
        let missing = in_order(vec![(p("a"), shard(1, 3), 0)]);
        assert!(
            missing
                .unwrap_err()
                .to_string()
                .contains("missing 2/3, 3/3")
        );
        let other = in_order(vec![(p("a"), shard(1, 2), 0), (p("c"), shard(1, 3), 0)]);
        assert!(other.unwrap_err().to_string().contains("not shard 1/3"));
        let plain = in_order(vec![(p("a"), None, 0)]);
        assert!(
            plain
                .unwrap_err()
                .to_string()
                .contains("made by a run with shard K/N")
        );
    }
}
