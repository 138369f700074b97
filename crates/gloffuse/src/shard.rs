//! Splitting one run into shards that farm nodes run apart (`--shard K/N`), and checking a
//! set of shard reports before they are merged. The split is a pure function of the items'
//! estimated costs, so every node, given the same inputs, computes the same split and takes
//! its own part: no queue, no coordinator.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
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
    // A report is data anyone who can write its folder may have edited: its numbers size
    // and index nothing. The shards are placed by index in a map as large as the reports
    // given, whatever count they claim.
    let first = shards[0].0.clone();
    let mut placed: BTreeMap<usize, (PathBuf, T)> = BTreeMap::new();
    for (path, shard, report) in shards {
        if let Some(s) = shard.filter(|s| s.index == 0 || s.index > s.count) {
            return Err(Error::input(
                Field::ShardReport,
                path.display(),
                format!(
                    "a shard K/N with 1 ≤ K ≤ N, not {}/{} (was it edited?)",
                    s.index, s.count
                ),
            ));
        }
        let Some(shard) = shard.filter(|s| s.count == count) else {
            let what = match shard {
                Some(s) => Hint::text(format!("shard {s}")),
                None => Hint::new("a report made without {}", [Field::Shard]),
            };
            return Err(Error::input(
                Field::ShardReport,
                path.display(),
                Hint::text(format!(
                    "a shard of {count} like the first report ({}), not ",
                    first.display()
                ))
                .then(what),
            ));
        };
        if let Some((other, _)) = placed.get(&shard.index) {
            return Err(Error::input(
                Field::ShardReport,
                path.display(),
                Hint::text(format!(
                    "each shard once: shard {shard} is also {}",
                    other.display()
                )),
            ));
        }
        placed.insert(shard.index, (path, report));
    }
    if placed.len() < count {
        return Err(missing(count, &placed, &first));
    }
    Ok(placed.into_values().collect())
}

/// The error of shards of `count` of which only those `placed` were given, `first` the
/// report that gives the count: the first few missing, found in as many steps as there are
/// reports (a count may be 10¹⁵).
fn missing<T>(count: usize, placed: &BTreeMap<usize, T>, first: &Path) -> Error {
    const SHOWN: usize = 10;
    let mut missing: Vec<String> = (1..=count)
        .filter(|k| !placed.contains_key(k))
        .take(SHOWN)
        .map(|k| format!("{k}/{count}"))
        .collect();
    let more = count - placed.len() - missing.len();
    if more > 0 {
        missing.push(format!("and {more} more"));
    }
    Error::input(
        Field::ShardReport,
        format!("{} reports", placed.len()),
        Hint::new(
            format!(
                "every shard of {count}, as {} says: missing {} (its report.json or {{}} \
                 folder)",
                first.display(),
                missing.join(", ")
            ),
            [Field::Report],
        ),
    )
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
        let huge = in_order(vec![
            (p("a"), shard(1, usize::MAX), 0),
            (p("b"), shard(2, 2), 0),
        ]);
        assert!(huge.unwrap_err().to_string().contains("first report (a)"));
        let alone = in_order(vec![(p("a"), shard(3, 1 << 50), 0)]).unwrap_err();
        assert!(
            alone.to_string().contains(&format!(
                "as a says: missing 1/{n}, 2/{n}, 4/{n}, 5/{n}, 6/{n}, 7/{n}, 8/{n}, 9/{n}, \
                 10/{n}, 11/{n}, and {} more",
                (1usize << 50) - 11,
                n = 1usize << 50
            )),
            "{alone}"
        );
        let zero = in_order(vec![(p("a"), shard(1, 2), 0), (p("z"), shard(0, 2), 0)]);
        assert!(zero.unwrap_err().to_string().contains("'z'"));
        let above = in_order(vec![(p("y"), shard(3, 2), 0), (p("a"), shard(1, 2), 0)]);
        assert!(above.unwrap_err().to_string().contains("'y'"));
        let plain = in_order(vec![(p("a"), None, 0)]);
        assert!(
            plain
                .unwrap_err()
                .to_string()
                .contains("made by a run with shard K/N")
        );
    }
}
