//! "Did you mean": the accepted name closest to a misspelt one, offered only when it is close.

/// How alike two names must be (Jaro–Winkler similarity, 1 = equal) for the one to be offered
/// for the other. At 0.85 a dropped, doubled or swapped letter qualifies ("coton" for "cotton":
/// 0.96, "densty_kg_m2" for "density_kg_m2": 0.98), and so does a key missing its unit suffix
/// ("density" for "density_kg_m2": 0.91, as the similarity favours a shared prefix), while
/// names that share a few letters do not ("tweed" for "denim": 0.47, "wool" for "silk": 0.50).
const MIN_SIMILARITY: f64 = 0.85;

/// The choice most like `word`, if it is like enough.
pub fn closest<'a>(word: &str, choices: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let word = word.to_lowercase();
    choices
        .into_iter()
        .map(|c| (strsim::jaro_winkler(&word, &c.to_lowercase()), c))
        .filter(|(score, _)| *score >= MIN_SIMILARITY)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, c)| c)
}

/// `; did you mean "x"?` for the closest choice, or nothing: to append to a problem.
pub fn did_you_mean<'a>(word: &str, choices: impl IntoIterator<Item = &'a str>) -> String {
    closest(word, choices).map_or_else(String::new, |c| format!("; did you mean {c:?}?"))
}

#[cfg(test)]
mod tests {
    use super::*;

    const PRESETS: [&str; 7] = [
        "cotton",
        "denim",
        "silk",
        "polyester",
        "jersey",
        "wool",
        "leather",
    ];
    const FABRIC_KEYS: [&str; 5] = [
        "preset",
        "density_kg_m2",
        "stretch_stiffness_n_m",
        "bending_stiffness_n_m",
        "damping_ratio",
    ];

    #[test]
    fn misspellings_find_their_name() {
        assert_eq!(closest("coton", PRESETS), Some("cotton"));
        assert_eq!(closest("Denim", PRESETS), Some("denim"));
        assert_eq!(closest("jersy", PRESETS), Some("jersey"));
        assert_eq!(closest("polyster", PRESETS), Some("polyester"));
        assert_eq!(closest("densty_kg_m2", FABRIC_KEYS), Some("density_kg_m2"));
        assert_eq!(closest("density", FABRIC_KEYS), Some("density_kg_m2"));
        assert_eq!(
            closest("stretch_stiffness", FABRIC_KEYS),
            Some("stretch_stiffness_n_m")
        );
        assert_eq!(
            closest("solvr", ["cloth", "solver", "world"]),
            Some("solver")
        );
    }

    #[test]
    fn unrelated_names_find_nothing() {
        assert_eq!(closest("tweed", PRESETS), None);
        assert_eq!(closest("velvet", PRESETS), None);
        assert_eq!(closest("gravity", FABRIC_KEYS), None);
        assert_eq!(did_you_mean("tweed", PRESETS), "");
        assert_eq!(did_you_mean("coton", PRESETS), "; did you mean \"cotton\"?");
    }
}
