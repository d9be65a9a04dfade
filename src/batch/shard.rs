//! Sharding: which manifest items one process runs. A pure function of the item's index, so
//! every process that reads the same manifest agrees without talking to the others.

use std::fmt;
use std::str::FromStr;

/// Shard `index` of `count`: the items whose 0-based position in the manifest is `index` modulo
/// `count`. Round-robin rather than contiguous blocks, so a manifest sorted by cost (e.g. by
/// particle spacing) spreads its slow items over all shards.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// 0-based shard index, below `count`.
    pub index: u32,
    /// Number of shards, at least 1.
    pub count: u32,
}

impl Shard {
    /// The whole manifest.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// A shard, checked.
    pub fn new(index: u32, count: u32) -> Result<Shard, String> {
        if count == 0 {
            return Err("the shard count must be at least 1".into());
        }
        if index >= count {
            return Err(format!(
                "shard {index} of {count} does not exist (shards are numbered 0 to {})",
                count - 1
            ));
        }
        Ok(Shard { index, count })
    }

    /// Whether item `k` (0-based position among the manifest's items) belongs to this shard.
    pub fn owns(&self, k: usize) -> bool {
        k % self.count as usize == self.index as usize
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;
    /// "i/n", e.g. "0/3".
    fn from_str(s: &str) -> Result<Shard, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("{s:?} is not INDEX/COUNT, e.g. 0/3"))?;
        let num = |v: &str| -> Result<u32, String> {
            v.trim()
                .parse()
                .map_err(|_| format!("{v:?} in {s:?} is not a whole number"))
        };
        Shard::new(num(i)?, num(n)?)
    }
}

/// Picks the shard, in this order: `--shard i/n`; a Slurm job array (`SLURM_ARRAY_TASK_ID` is
/// the index, the count is `--shards` when given, else `SLURM_ARRAY_TASK_COUNT`); Kubernetes'
/// `JOB_COMPLETION_INDEX` with the count from `--shards`; else the whole manifest. `--shards`
/// with Slurm resubmits some shards: `sbatch --array=1,3 …` with `--shards 4` reruns shards 1
/// and 3 of 4. `env` reads a variable (injected for tests).
pub fn resolve(
    flag: Option<Shard>,
    shards: Option<u32>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<(Shard, &'static str), String> {
    if shards == Some(0) {
        return Err(
            "--shards 0: a manifest is split into 1 or more shards; give --shards 1 \
                    or more"
                .into(),
        );
    }
    if let Some(s) = flag {
        if shards.is_some_and(|n| n != s.count) {
            return Err(format!(
                "--shard {s} and --shards {} disagree",
                shards.unwrap()
            ));
        }
        return Ok((s, "--shard"));
    }
    let var = |name: &str| -> Result<Option<i64>, String> {
        match env(name) {
            None => Ok(None),
            Some(v) if v.trim().is_empty() => Ok(None),
            Some(v) => v
                .trim()
                .parse()
                .map(Some)
                .map_err(|_| format!("{name}={v:?} is not a whole number")),
        }
    };
    if let Some(id) = var("SLURM_ARRAY_TASK_ID")? {
        let count = match shards {
            Some(n) => n as i64,
            None => {
                // The task id is the shard index, so the array must be 0, 1, …, N−1.
                let min = var("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
                let step = var("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1);
                if min != 0 || step != 1 {
                    return Err(format!(
                        "the job array starts at {min} with step {step}: submit \
                         --array=0-(N-1), or give --shards N to use the task ids as shard \
                         indices"
                    ));
                }
                var("SLURM_ARRAY_TASK_COUNT")?
                    .ok_or("SLURM_ARRAY_TASK_ID is set but SLURM_ARRAY_TASK_COUNT is not")?
            }
        };
        let shard = Shard::new(to_u32(id)?, to_u32(count)?)
            .map_err(|e| format!("from SLURM_ARRAY_TASK_ID={id}: {e}"))?;
        return Ok((shard, "SLURM_ARRAY_TASK_ID"));
    }
    if let Some(index) = var("JOB_COMPLETION_INDEX")? {
        let count = shards
            .ok_or("JOB_COMPLETION_INDEX is set: give the Job's completions as --shards N")?;
        let shard = Shard::new(to_u32(index)?, count)
            .map_err(|e| format!("from JOB_COMPLETION_INDEX and --shards: {e}"))?;
        return Ok((shard, "JOB_COMPLETION_INDEX"));
    }
    if let Some(n) = shards {
        return Err(format!(
            "--shards {n} without a shard index: give --shard i/{n}, or run under a Slurm \
             array or a Kubernetes indexed Job"
        ));
    }
    Ok((Shard::ALL, "whole manifest"))
}

fn to_u32(v: i64) -> Result<u32, String> {
    u32::try_from(v).map_err(|_| format!("{v} is not a shard number"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |name| {
            vars.iter()
                .find(|(k, _)| *k == name)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn every_item_belongs_to_exactly_one_shard() {
        for n in 1..7u32 {
            for k in 0..50 {
                let owners = (0..n).filter(|&i| Shard::new(i, n).unwrap().owns(k));
                assert_eq!(owners.collect::<Vec<_>>(), vec![k as u32 % n]);
            }
        }
    }

    #[test]
    fn parses_and_refuses_shard_flags() {
        assert_eq!("1/3".parse::<Shard>(), Ok(Shard { index: 1, count: 3 }));
        assert!("3/3".parse::<Shard>().unwrap_err().contains("0 to 2"));
        assert!("0/0".parse::<Shard>().is_err());
        assert!("1-3".parse::<Shard>().is_err());
        assert!("a/3".parse::<Shard>().is_err());
    }

    #[test]
    fn the_flag_wins_then_slurm_then_kubernetes_then_everything() {
        let slurm = [
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        let flag = Shard::new(1, 3).unwrap();
        assert_eq!(resolve(Some(flag), None, &env(&slurm)).unwrap().0, flag);
        assert_eq!(
            resolve(None, None, &env(&slurm)).unwrap().0,
            Shard::new(2, 4).unwrap()
        );
        let k8s = [("JOB_COMPLETION_INDEX", "5")];
        assert_eq!(
            resolve(None, Some(8), &env(&k8s)).unwrap().0,
            Shard::new(5, 8).unwrap()
        );
        assert!(resolve(None, None, &env(&k8s))
            .unwrap_err()
            .contains("--shards"));
        assert_eq!(resolve(None, None, &env(&[])).unwrap().0, Shard::ALL);
        assert!(resolve(None, Some(3), &env(&[])).is_err());
        // Zero shards is no split: said as such, not "give --shard i/0".
        let zero = resolve(None, Some(0), &env(&k8s)).unwrap_err();
        assert!(zero.contains("give --shards 1 or more"), "{zero}");
    }

    #[test]
    fn slurm_arrays_start_at_zero_unless_shards_is_given() {
        let offset = [
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
        ];
        assert!(resolve(None, None, &env(&offset))
            .unwrap_err()
            .contains("--array=0-"));
        // Resubmitting shard 1 of 4 alone: an array of one task, id 1.
        let resubmit = [
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "1"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
        ];
        assert_eq!(
            resolve(None, Some(4), &env(&resubmit)).unwrap().0,
            Shard::new(1, 4).unwrap()
        );
        assert!(resolve(None, None, &env(&resubmit)).is_err());
        let bad = [
            ("SLURM_ARRAY_TASK_ID", "x"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert!(resolve(None, None, &env(&bad)).is_err());
    }
}
