//! Properties of keys, descriptions and `explain`.

use std::collections::HashMap;

use crate::cache::{ContentHash, Key, KeyBuilder, KeyDescription, KeyError, Param, explain};

fn hash(text: &str) -> ContentHash {
    ContentHash::of(text.as_bytes())
}

/// Everything a key is built from, as plain data, so a test can change exactly one thing.
#[derive(Clone)]
struct Spec {
    kind: &'static str,
    version: u32,
    params: Vec<(&'static str, Param)>,
    inputs: Vec<(&'static str, ContentHash)>,
}

impl Spec {
    /// A contour-like stage: the baseline every "change one thing" test perturbs.
    fn base() -> Spec {
        Spec {
            kind: "contour",
            version: 1,
            params: vec![
                ("offset", 0.1.into()),
                ("resolution", 64u32.into()),
                ("formats", Param::List(vec!["stl".into(), "3mf".into()])),
                ("closed", true.into()),
                ("shift", (-3i64).into()),
                ("seed", Param::Bytes(vec![1, 2, 3])),
            ],
            inputs: vec![
                ("cell", hash("cell bytes")),
                ("scaffold", hash("scaffold bytes")),
            ],
        }
    }

    fn builder(&self) -> KeyBuilder {
        let b = KeyBuilder::new(self.kind, self.version);
        let b = self
            .params
            .iter()
            .fold(b, |b, (name, value)| b.param(name, value.clone()));
        self.inputs
            .iter()
            .fold(b, |b, (name, hash)| b.input(name, *hash))
    }

    fn build(&self) -> (Key, KeyDescription) {
        self.builder().build().expect("names are unique")
    }

    fn key(&self) -> Key {
        self.build().0
    }

    fn with(mut self, change: impl FnOnce(&mut Spec)) -> Spec {
        change(&mut self);
        self
    }

    fn set(self, name: &'static str, value: impl Into<Param>) -> Spec {
        let value = value.into();
        self.with(|s| match s.params.iter_mut().find(|(n, _)| *n == name) {
            Some(slot) => slot.1 = value,
            None => s.params.push((name, value)),
        })
    }

    fn set_input(self, name: &'static str, hash: ContentHash) -> Spec {
        self.with(|s| match s.inputs.iter_mut().find(|(n, _)| *n == name) {
            Some(slot) => slot.1 = hash,
            None => s.inputs.push((name, hash)),
        })
    }

    fn without(self, name: &str) -> Spec {
        self.with(|s| s.params.retain(|(n, _)| *n != name))
    }
}

#[test]
fn insertion_order_does_not_matter() {
    let forward = Spec::base();
    let backward = Spec::base().with(|s| {
        s.params.reverse();
        s.inputs.reverse();
    });
    assert_eq!(forward.build(), backward.build());
}

#[test]
fn hash_map_iteration_order_cannot_leak_in() {
    // Same content, inserted in opposite orders: the maps' iteration orders (almost surely)
    // differ, and so would a key that depended on them.
    let mut first = HashMap::new();
    let mut second = HashMap::new();
    for i in 0..64u64 {
        first.insert(format!("p{i}"), i);
    }
    for i in (0..64u64).rev() {
        second.insert(format!("p{i}"), i);
    }
    let key_of = |map: &HashMap<String, u64>| {
        map.iter()
            .fold(KeyBuilder::new("fit", 1), |b, (n, v)| b.param(n, *v))
            .build()
            .unwrap()
            .0
    };
    assert_eq!(key_of(&first), key_of(&second));
}

#[test]
fn zero_and_negative_zero_differ() {
    let pos = Spec::base().set("offset", 0.0);
    let neg = Spec::base().set("offset", -0.0);
    assert_ne!(pos.key(), neg.key());
}

#[test]
fn nan_is_its_bits() {
    let quiet = f64::from_bits(0x7ff8_0000_0000_0000);
    let other = f64::from_bits(0x7ff8_0000_0000_0001);
    let a = Spec::base().set("offset", quiet);
    assert_eq!(a.key(), a.key(), "a NaN must not make a key unstable");
    assert_ne!(a.key(), Spec::base().set("offset", other).key());
}

#[test]
fn changing_any_single_thing_changes_the_key() {
    let reference = Spec::base().key();
    let variants: Vec<(&str, Spec)> = vec![
        ("kind", Spec::base().with(|s| s.kind = "fit")),
        ("version", Spec::base().with(|s| s.version = 2)),
        ("offset", Spec::base().set("offset", 0.2)),
        (
            "offset by one ulp",
            Spec::base().set("offset", 0.1f64.next_up()),
        ),
        ("resolution", Spec::base().set("resolution", 65u32)),
        ("resolution's type", Spec::base().set("resolution", 64i64)),
        ("closed", Spec::base().set("closed", false)),
        ("shift", Spec::base().set("shift", 3i64)),
        (
            "seed",
            Spec::base().set("seed", Param::Bytes(vec![1, 2, 4])),
        ),
        (
            "seed's type",
            Spec::base().set("seed", Param::from([1u32, 2, 3])),
        ),
        (
            "formats' order",
            Spec::base().set("formats", Param::List(vec!["3mf".into(), "stl".into()])),
        ),
        (
            "formats' length",
            Spec::base().set("formats", Param::List(vec!["stl".into()])),
        ),
        (
            "formats' string boundaries",
            Spec::base().set("formats", Param::List(vec!["st".into(), "l3mf".into()])),
        ),
        ("an added parameter", Spec::base().set("quality", 1u64)),
        ("a removed parameter", Spec::base().without("closed")),
        (
            "a renamed parameter",
            Spec::base().with(|s| s.params[0].0 = "offset_mm"),
        ),
        (
            "input cell",
            Spec::base().set_input("cell", hash("other cell")),
        ),
        (
            "input scaffold",
            Spec::base().set_input("scaffold", hash("other")),
        ),
        (
            "an added input",
            Spec::base().set_input("field", hash("field")),
        ),
        (
            "a renamed input",
            Spec::base().with(|s| s.inputs[0].0 = "cell2"),
        ),
        // The same name as a parameter and as an input are different things.
        (
            "a parameter turned input",
            Spec::base().without("seed").set_input("seed", hash("seed")),
        ),
    ];
    let mut keys: Vec<Key> = vec![reference];
    for (what, spec) in &variants {
        let key = spec.key();
        assert_ne!(key, reference, "changing {what} must change the key");
        keys.push(key);
    }
    // The variants also differ from one another, not merely from the reference.
    keys.sort();
    keys.dedup();
    assert_eq!(keys.len(), variants.len() + 1);
}

#[test]
fn duplicate_names_are_an_error_not_a_silent_choice() {
    let err = KeyBuilder::new("fit", 1)
        .param("offset", 0.1)
        .param("offset", 0.2)
        .build()
        .unwrap_err();
    assert_eq!(
        err,
        KeyError::DuplicateParameter {
            kind: "fit".into(),
            name: "offset".into()
        }
    );
    let err = KeyBuilder::new("fit", 1)
        .input("cell", hash("a"))
        .input("cell", hash("a"))
        .build()
        .unwrap_err();
    assert!(matches!(err, KeyError::DuplicateInput { ref name, .. } if name == "cell"));
    // A parameter and an input may share a name: they are separate namespaces.
    assert!(
        KeyBuilder::new("fit", 1)
            .param("cell", 1u64)
            .input("cell", hash("a"))
            .build()
            .is_ok()
    );
}

/// If this fails, the key encoding changed by accident: every user's cache silently misses (or
/// worse, an old entry is read under a new meaning). If the change is deliberate, change
/// `KEY_CONTEXT` and bump the affected stage versions, then update this literal.
#[test]
fn key_is_stable_across_runs_and_machines() {
    let (key, _) = Spec::base().build();
    assert_eq!(
        key.to_string(),
        "0c83b6a07fa10c73580ed618319b7bfff45c27972024def732a046d5f2ccd9f0"
    );
}

#[test]
fn description_is_sorted_readable_and_round_trips_through_json() {
    let (_, description) = Spec::base().build();
    let names: Vec<&str> = description.params.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        ["closed", "formats", "offset", "resolution", "seed", "shift"]
    );
    let values: Vec<&str> = description
        .params
        .iter()
        .map(|p| p.value.as_str())
        .collect();
    assert_eq!(
        values,
        ["true", r#"["stl", "3mf"]"#, "0.1", "64", "0x010203", "-3"]
    );
    assert_eq!(description.inputs[0].name, "cell");
    assert_eq!(description.inputs[0].hash, hash("cell bytes"));

    let json = serde_json::to_string(&description).unwrap();
    let back: KeyDescription = serde_json::from_str(&json).unwrap();
    assert_eq!(back, description);
}

#[test]
fn renderings_show_what_was_hashed() {
    let render = |p: Param| {
        let (_, d) = KeyBuilder::new("k", 1).param("p", p).build().unwrap();
        d.params[0].value.clone()
    };
    assert_eq!(render((-0.0).into()), "-0.0");
    assert_eq!(render(1e300.into()), "1e300");
    assert_eq!(render(f64::NAN.into()), "NaN");
    assert_eq!(
        render(f64::from_bits(0x7ff8_0000_0000_0001).into()),
        "NaN(0x7ff8000000000001)"
    );
    assert_eq!(render("a \"b\"\n".into()), r#""a \"b\"\n""#);
    assert_eq!(render(Param::Bytes(vec![0; 100])), "<100 bytes>");
    // A huge list is cut, not rendered in full.
    let long = render(Param::List((0..100_000u64).map(Param::U64).collect()));
    assert_eq!(long.chars().count(), 160);
    assert!(long.ends_with('…'));
}

fn explain_change(change: impl FnOnce(Spec) -> Spec) -> Vec<String> {
    let (_, before) = Spec::base().build();
    let (_, after) = change(Spec::base()).build();
    explain(&before, &after)
}

#[test]
fn explain_names_each_kind_of_change() {
    assert_eq!(explain_change(|s| s), Vec::<String>::new());
    assert_eq!(
        explain_change(|s| s.set("offset", 0.2)),
        ["parameter `offset` changed: 0.1 → 0.2"]
    );
    assert_eq!(
        explain_change(|s| s.with(|s| s.version = 2)),
        ["stage version changed: 1 → 2"]
    );
    assert_eq!(
        explain_change(|s| s.with(|s| s.kind = "fit")),
        ["stage kind changed: contour → fit"]
    );
    assert_eq!(
        explain_change(|s| s.set_input("cell", hash("new cell"))),
        ["input `cell` changed"]
    );
    assert_eq!(
        explain_change(|s| s.set_input("field", hash("f"))),
        ["input `field` added"]
    );
    assert_eq!(
        explain_change(|s| s.with(|s| s.inputs.retain(|(n, _)| *n != "scaffold"))),
        ["input `scaffold` removed"]
    );
    assert_eq!(
        explain_change(|s| s.set("quality", "high")),
        [r#"parameter `quality` added: "high""#]
    );
    assert_eq!(
        explain_change(|s| s.without("formats")),
        [r#"parameter `formats` removed (was ["stl", "3mf"])"#]
    );
    assert_eq!(
        explain_change(|s| s.set("resolution", 64i64)),
        ["parameter `resolution` changed: 64 → 64 (same text, different type or bits)"]
    );
}

#[test]
fn explain_lists_several_changes_in_a_fixed_order() {
    let lines = explain_change(|s| {
        s.with(|s| s.version = 3)
            .set("shift", 4i64)
            .set("closed", false)
            .set_input("scaffold", hash("s2"))
            .set_input("cell", hash("c2"))
    });
    assert_eq!(
        lines,
        [
            "stage version changed: 1 → 3",
            "parameter `closed` changed: true → false",
            "parameter `shift` changed: -3 → 4",
            "input `cell` changed",
            "input `scaffold` changed",
        ]
    );
}

#[test]
fn explain_does_not_trust_the_order_of_a_stored_description() {
    let (_, before) = Spec::base().build();
    let (_, after) = Spec::base().set("offset", 0.3).build();
    let mut shuffled = before.clone();
    shuffled.params.reverse();
    shuffled.inputs.reverse();
    assert_eq!(explain(&shuffled, &after), explain(&before, &after));
}

#[test]
fn key_and_hash_text_round_trip_and_reject_other_spellings() {
    let key = Spec::base().key();
    let text = key.to_string();
    assert_eq!(text.parse::<Key>(), Ok(key));
    assert!(text.to_uppercase().parse::<Key>().is_err());
    assert!(text[1..].parse::<Key>().is_err());
    let json = serde_json::to_string(&key).unwrap();
    assert_eq!(json, format!("\"{text}\""));
    assert!(serde_json::from_str::<Key>("\"nothex\"").is_err());
}

#[test]
fn content_hash_is_the_same_serial_and_parallel() {
    // 3 MiB takes the rayon path; the digest must equal plain blake3 (thread count never shows).
    let data: Vec<u8> = (0..3u32 << 20).map(|i| (i % 251) as u8).collect();
    assert_eq!(
        ContentHash::of(&data).as_bytes(),
        blake3::hash(&data).as_bytes()
    );
}

/// Re-derives one key byte by byte from the tables in `key.rs` and `param.rs`, so the
/// documentation and the code cannot drift apart.
#[test]
fn key_matches_the_documented_encoding() {
    let cell = hash("cell");
    let (key, _) = KeyBuilder::new("fit", 7)
        .param("tags", Param::List(vec!["a".into(), Param::Bool(true)]))
        .param("offset", -0.0)
        .input("cell", cell)
        .build()
        .unwrap();

    let mut bytes = Vec::new();
    let le64 = |v: u64| v.to_le_bytes();
    bytes.extend(le64(3));
    bytes.extend(b"fit");
    bytes.extend(7u32.to_le_bytes());
    bytes.extend(le64(2)); // parameters, sorted: offset, tags
    bytes.extend(le64(6));
    bytes.extend(b"offset");
    bytes.push(0x03);
    bytes.extend(le64(0x8000_0000_0000_0000));
    bytes.extend(le64(4));
    bytes.extend(b"tags");
    bytes.push(0x07);
    bytes.extend(le64(2));
    bytes.push(0x05);
    bytes.extend(le64(1));
    bytes.extend(b"a");
    bytes.push(0x04);
    bytes.push(1);
    bytes.extend(le64(1)); // inputs
    bytes.extend(le64(4));
    bytes.extend(b"cell");
    bytes.extend(cell.as_bytes());

    let expected = blake3::derive_key(crate::cache::KEY_CONTEXT, &bytes);
    assert_eq!(key.as_bytes(), &expected);
}
