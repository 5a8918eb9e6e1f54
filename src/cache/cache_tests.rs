//! Properties of `Cache`: location, locking, records, `peek_hash`, `clean` and `gc`.

use std::collections::HashSet;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::thread;
use std::time::Duration;

use crate::cache::{
    Cache, CacheError, ContentHash, Key, KeyBuilder, KeyDescription, Lookup, Record, SizeLimit,
    record,
};

fn manifest() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lattice.toml");
    fs::write(&path, "# a manifest\n").unwrap();
    (dir, path)
}

fn keyed(n: u64) -> (Key, KeyDescription) {
    KeyBuilder::new("contour", 1)
        .param("offset", n as f64 / 10.0)
        .input("cell", ContentHash::of(b"cell"))
        .build()
        .unwrap()
}

fn is_miss(lookup: Lookup) -> bool {
    matches!(lookup, Lookup::Miss)
}

#[test]
fn lives_next_to_the_manifest_under_its_file_name() {
    let (dir, path) = manifest();
    let cache = Cache::open(&path).unwrap();
    let expected = dir.path().join(".latticebuild").join("lattice.toml");
    assert_eq!(cache.dir(), expected);
    assert!(expected.join("lock").is_file());
    assert!(dir.path().join(".latticebuild/CACHEDIR.TAG").is_file());
    assert_eq!(
        fs::read_to_string(dir.path().join(".latticebuild/.gitignore")).unwrap(),
        "*\n"
    );
}

#[test]
fn a_path_without_a_file_name_is_an_error_naming_it() {
    let err = Cache::open(Path::new("/")).unwrap_err();
    assert!(matches!(err, CacheError::NotAManifestFile { .. }));
    assert!(err.to_string().contains("`/`"), "{err}");
}

#[test]
fn two_manifests_in_one_directory_have_separate_caches_and_locks() {
    let (dir, path) = manifest();
    let other = dir.path().join("other.toml");
    let first = Cache::open(&path).unwrap();
    // Would block forever if the two manifests shared a lock.
    let second = Cache::open_with(&other, || panic!("must not wait")).unwrap();
    let (k, _) = keyed(1);
    first.put(&k, b"first").unwrap();
    assert!(is_miss(second.get(&k).unwrap()));
}

#[test]
fn a_second_open_waits_for_the_first_to_be_dropped() {
    let (_dir, path) = manifest();
    let first = Cache::open_with(&path, || panic!("the lock is free; must not wait")).unwrap();

    let first_dropped = Arc::new(AtomicBool::new(false));
    let (waiting_tx, waiting_rx) = mpsc::channel();
    let (opened_tx, opened_rx) = mpsc::channel();
    let second = {
        let (path, first_dropped) = (path.clone(), first_dropped.clone());
        thread::spawn(move || {
            let cache = Cache::open_with(&path, move || waiting_tx.send(()).unwrap()).unwrap();
            // The lock was granted: the first Cache must already be gone.
            opened_tx
                .send(first_dropped.load(Ordering::SeqCst))
                .unwrap();
            drop(cache);
        })
    };

    waiting_rx
        .recv_timeout(Duration::from_secs(30))
        .expect("the second open must report that it waits");
    // Give a wrongly non-blocking open the chance to finish; the flag check below is what
    // proves the order, this only makes a failure show up here rather than as a flag.
    assert!(
        opened_rx.recv_timeout(Duration::from_millis(200)).is_err(),
        "the second open returned while the first Cache was alive"
    );
    first_dropped.store(true, Ordering::SeqCst);
    drop(first);
    let saw_drop = opened_rx
        .recv_timeout(Duration::from_secs(30))
        .expect("the second open must succeed once the first Cache is dropped");
    assert!(
        saw_drop,
        "the second open was granted before the first Cache was dropped"
    );
    second.join().unwrap();
}

#[test]
fn records_round_trip_and_explain_the_next_build() {
    let (_dir, path) = manifest();
    let cache = Cache::open(&path).unwrap();
    let node = "contour:outputs.g";
    assert_eq!(cache.previous(node), None);

    let (k1, d1) = keyed(1);
    let out1 = cache.put(&k1, b"mesh 1").unwrap();
    cache.record(node, &k1, &d1, &out1).unwrap();
    let expected = Record {
        node: node.into(),
        key: k1,
        description: d1.clone(),
        output: out1,
    };
    assert_eq!(cache.previous(node), Some(expected.clone()));
    assert_eq!(cache.records().unwrap(), [expected]);

    // A reopened cache (the next build) sees the record and can say why the key moved.
    drop(cache);
    let cache = Cache::open(&path).unwrap();
    let (k2, d2) = keyed(2);
    let previous = cache.previous(node).unwrap();
    assert_ne!(previous.key, k2);
    assert_eq!(
        crate::cache::explain(&previous.description, &d2),
        ["parameter `offset` changed: 0.1 → 0.2"]
    );
    let out2 = cache.put(&k2, b"mesh 2").unwrap();
    cache.record(node, &k2, &d2, &out2).unwrap();
    assert_eq!(cache.previous(node).unwrap().key, k2);
}

#[test]
fn record_file_names_are_safe_and_distinct() {
    let long = "x".repeat(1000);
    let long_other = format!("{}y", "x".repeat(999));
    let names = [
        "contour:outputs.g",
        "Contour:outputs.g",
        "contour%3Aoutputs.g",
        "a/b",
        "a\\b",
        "..",
        ".",
        "",
        "~",
        "é",
        "sample:cells.p",
        long.as_str(),
        long_other.as_str(),
    ];
    let files: Vec<String> = names.iter().map(|n| record::file_name(n)).collect();
    for (name, file) in names.iter().zip(&files) {
        assert!(file.len() <= 200, "{name:?} → {file:?} is too long");
        assert!(!file.starts_with('.'), "{name:?} → {file:?} is hidden");
        let safe = file
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b"%.-_~ABCDEF".contains(&b));
        assert!(safe, "{name:?} → {file:?} has an unsafe character");
    }
    assert_eq!(files[0], "contour%3Aoutputs.g.json");
    // Distinct even when compared case-insensitively (macOS, Windows).
    let folded: HashSet<String> = files.iter().map(|f| f.to_lowercase()).collect();
    assert_eq!(folded.len(), names.len());

    // And each really gets its own record.
    let (_dir, path) = manifest();
    let cache = Cache::open(&path).unwrap();
    let (k, d) = keyed(1);
    let out = ContentHash::of(b"out");
    for name in names {
        cache.record(name, &k, &d, &out).unwrap();
    }
    for name in names {
        assert_eq!(cache.previous(name).unwrap().node, name);
    }
    assert_eq!(cache.records().unwrap().len(), names.len());
}

#[test]
fn unreadable_records_are_absent_not_errors() {
    let (_dir, path) = manifest();
    let cache = Cache::open(&path).unwrap();
    let records = cache.dir().join("records");
    fs::create_dir_all(&records).unwrap();
    fs::write(records.join(record::file_name("broken")), b"{ not json").unwrap();
    assert_eq!(cache.previous("broken"), None);
    assert_eq!(cache.records().unwrap(), []);
}

#[test]
fn peek_hash_reads_the_header_only() {
    let (_dir, path) = manifest();
    let cache = Cache::open(&path).unwrap();
    let (k, _) = keyed(1);
    assert_eq!(cache.peek_hash(&k), None);
    let put_hash = cache.put(&k, &[7u8; 10_000]).unwrap();
    assert_eq!(cache.peek_hash(&k), Some(put_hash));

    // Corrupt the payload: a full read would notice, a header-only peek cannot.
    let entry = cache.store().entry_path(&k);
    let mut bytes = fs::read(&entry).unwrap();
    bytes[48 + 5000] ^= 0xff;
    fs::write(&entry, bytes).unwrap();
    assert_eq!(cache.peek_hash(&k), Some(put_hash));
    assert!(matches!(cache.get(&k).unwrap(), Lookup::Corrupt { .. }));
}

#[test]
fn clean_empties_everything_but_the_held_lock() {
    let (_dir, path) = manifest();
    let mut cache = Cache::open(&path).unwrap();
    let (k, d) = keyed(1);
    let out = cache.put(&k, b"mesh").unwrap();
    cache.record("contour:g", &k, &d, &out).unwrap();

    cache.clean().unwrap();
    let left: Vec<String> = fs::read_dir(cache.dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(left, ["lock"]);
    assert!(is_miss(cache.get(&k).unwrap()));
    assert_eq!(cache.previous("contour:g"), None);

    // Still usable, and still locked.
    cache.put(&k, b"mesh").unwrap();
    assert!(matches!(cache.get(&k).unwrap(), Lookup::Hit { .. }));
    let lock = fs::File::open(cache.dir().join("lock")).unwrap();
    assert!(lock.try_lock().is_err(), "clean must not release the lock");
}

#[test]
fn gc_keeps_exactly_the_given_keys() {
    let (_dir, path) = manifest();
    let cache = Cache::open(&path).unwrap();
    let keys: Vec<Key> = (0..20).map(|n| keyed(n).0).collect();
    for (i, k) in keys.iter().enumerate() {
        cache.put(k, format!("mesh {i}").as_bytes()).unwrap();
    }
    let keep: HashSet<Key> = keys.iter().step_by(3).copied().collect();
    // A temp file from a crashed process (pid 0 is never ours) and one from this process
    // (which could be an in-flight put, so it must survive).
    let shard = cache
        .store()
        .entry_path(&keys[0])
        .parent()
        .unwrap()
        .to_path_buf();
    let crashed = shard.join(".tmp-0-5-00000000deadbeef");
    let ours = shard.join(format!(
        ".tmp-{}-999999-0000000000000000",
        std::process::id()
    ));
    fs::write(&crashed, b"junk").unwrap();
    fs::write(&ours, b"junk").unwrap();
    let foreign = shard.join("README");
    fs::write(&foreign, b"not ours to judge").unwrap();

    let removed = cache.gc(&keep, SizeLimit::bytes(0)).unwrap().removed;
    assert_eq!(removed, keys.len() - keep.len());
    for (i, k) in keys.iter().enumerate() {
        let kept = keep.contains(k);
        assert_eq!(cache.contains(k).unwrap(), kept, "key {i}");
        if kept {
            let (payload, _) = match cache.get(k).unwrap() {
                Lookup::Hit { payload, hash } => (payload, hash),
                other => panic!("key {i}: {other:?}"),
            };
            assert_eq!(payload, format!("mesh {i}").as_bytes());
        }
    }
    assert!(!crashed.exists());
    assert!(ours.exists());
    assert!(foreign.exists());
    assert_eq!(
        cache.gc(&keep, SizeLimit::bytes(0)).unwrap().removed,
        0,
        "gc is idempotent"
    );
}

#[test]
fn gc_evicts_the_least_recently_used_until_the_rest_fit() {
    let (_dir, path) = manifest();
    let cache = Cache::open(&path).unwrap();
    let keys: Vec<Key> = (0..5).map(|n| keyed(n).0).collect();
    let payload = vec![7u8; 1000];
    for k in &keys {
        cache.put(k, &payload).unwrap();
    }
    let entry_bytes = fs::metadata(cache.store().entry_path(&keys[0]))
        .unwrap()
        .len();
    // Use them in the order 3, 0, 4, 1, 2 (one build each), then a build that uses only 2.
    for &i in &[3usize, 0, 4, 1, 2] {
        thread::sleep(Duration::from_millis(20));
        let used = HashSet::from([keys[i]]);
        assert_eq!(
            cache.gc(&used, SizeLimit::bytes(u64::MAX)).unwrap().removed,
            0
        );
    }
    // Room for three entries: the two least recently used other than the one in use (3, 0)
    // go, and what is in use stays even under a limit that holds nothing.
    let collected = cache
        .gc(&HashSet::from([keys[2]]), SizeLimit::bytes(3 * entry_bytes))
        .unwrap();
    assert_eq!(collected.removed, 2);
    assert_eq!(collected.kept_bytes, 3 * entry_bytes);
    let present: Vec<bool> = keys.iter().map(|k| cache.contains(k).unwrap()).collect();
    assert_eq!(present, [false, true, true, false, true]);
    let collected = cache
        .gc(&HashSet::from([keys[4]]), SizeLimit::bytes(0))
        .unwrap();
    assert_eq!(collected.removed, 2, "1 and 2 go, 4 is in use");
    assert!(cache.contains(&keys[4]).unwrap());
    assert!(matches!(cache.get(&keys[4]).unwrap(), Lookup::Hit { .. }));
}

#[test]
fn the_limit_leaves_half_of_the_space_the_cache_could_have() {
    let limit = SizeLimit {
        max_bytes: 4_000,
        free_disk: Some(1_000),
    };
    assert_eq!(limit.allowed(2_000), 1_500, "(2000 + 1000) / 2");
    assert_eq!(limit.allowed(9_000), 4_000, "max_bytes is the bound");
    assert_eq!(SizeLimit::bytes(7).allowed(u64::MAX), 7);
}

#[test]
fn gc_survives_a_foreign_objects_directory() {
    let (_dir, path) = manifest();
    let cache = Cache::open(&path).unwrap();
    let objects = cache.dir().join("objects");
    fs::create_dir_all(objects.join("zz")).unwrap();
    fs::create_dir_all(objects.join("ab").join("nested")).unwrap();
    fs::write(objects.join("stray-file"), b"x").unwrap();
    assert_eq!(
        cache
            .gc(&HashSet::new(), SizeLimit::bytes(0))
            .unwrap()
            .removed,
        0
    );
}

#[test]
fn cache_and_store_can_be_shared_between_threads() {
    fn assert_send_sync<T: Send + Sync>() {}
    assert_send_sync::<Cache>();
    assert_send_sync::<crate::cache::LocalStore>();
    assert_send_sync::<Box<dyn crate::cache::Store>>();
}
