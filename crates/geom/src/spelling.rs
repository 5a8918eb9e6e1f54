//! Suggestions for misspelled names ("did you mean …?").
//!
//! Invariant: a suggestion is offered only when it is close enough to be a plausible typo:
//! an edit distance of at most a third of the longer name (at least 1), compared
//! case-insensitively. Ties go to the earliest candidate, so suggestions are deterministic.

/// The candidate closest to `word`, if any is close enough to be a likely typo.
pub fn closest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let word_lower = word.to_lowercase();
    let mut best: Option<(usize, &'a str)> = None;
    for candidate in candidates {
        let distance = edit_distance(&word_lower, &candidate.to_lowercase());
        let limit = (word.chars().count().max(candidate.chars().count()) / 3).max(1);
        if distance <= limit && best.is_none_or(|(d, _)| distance < d) {
            best = Some((distance, candidate));
        }
    }
    best.map(|(_, c)| c)
}

/// Optimal-string-alignment distance: insertions, deletions, substitutions and swaps of two
/// neighbouring characters each cost 1 (a swap is the most common typo in key names).
pub fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let width = b.len() + 1;
    let mut d = vec![0usize; (a.len() + 1) * width];
    for i in 0..=a.len() {
        d[i * width] = i;
    }
    for (j, cell) in d.iter_mut().enumerate().take(width) {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut v = (d[(i - 1) * width + j] + 1)
                .min(d[i * width + j - 1] + 1)
                .min(d[(i - 1) * width + j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                v = v.min(d[(i - 2) * width + j - 2] + 1);
            }
            d[i * width + j] = v;
        }
    }
    d[a.len() * width + b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_of_common_typos() {
        assert_eq!(edit_distance("samples", "samples"), 0);
        assert_eq!(edit_distance("sampels", "samples"), 1); // swap
        assert_eq!(edit_distance("gyroyd", "gyroid"), 1); // substitution
        assert_eq!(edit_distance("gyrid", "gyroid"), 1); // deletion
        assert_eq!(edit_distance("", "abc"), 3);
    }

    #[test]
    fn suggests_only_plausible_names() {
        let keys = ["samples", "voxel", "solid", "offset"];
        assert_eq!(closest("sampels", keys), Some("samples"));
        assert_eq!(closest("Solid", keys), Some("solid"));
        assert_eq!(closest("banana", keys), None);
        assert_eq!(closest("x", ["p", "d"]), Some("p"));
    }
}
