//! Properties of `LocalStore`: round trips, corruption handling, atomicity under concurrency.

use std::fs::{self, OpenOptions};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::thread;

use crate::cache::{ContentHash, Corruption, Key, KeyBuilder, LocalStore, Lookup, Store};

fn key(n: u64) -> Key {
    KeyBuilder::new("test", 1).param("n", n).build().unwrap().0
}

fn store() -> (tempfile::TempDir, LocalStore) {
    let dir = tempfile::tempdir().unwrap();
    let store = LocalStore::new(dir.path());
    (dir, store)
}

fn payload(len: usize, seed: u8) -> Vec<u8> {
    (0..len)
        .map(|i| (i as u8).wrapping_mul(31).wrapping_add(seed))
        .collect()
}

fn expect_hit(lookup: Lookup) -> (Vec<u8>, ContentHash) {
    match lookup {
        Lookup::Hit { payload, hash } => (payload, hash),
        other => panic!("expected a hit, got {other:?}"),
    }
}

fn expect_corrupt(lookup: Lookup) -> Corruption {
    match lookup {
        Lookup::Corrupt { reason } => reason,
        other => panic!("expected corruption, got {other:?}"),
    }
}

#[test]
fn round_trip_small_empty_and_large() {
    let (_dir, store) = store();
    // 3 MiB crosses the parallel-hashing threshold on both write and read.
    for (n, bytes) in [
        (1, payload(1000, 7)),
        (2, Vec::new()),
        (3, payload(3 << 20, 1)),
    ] {
        let k = key(n);
        assert!(matches!(store.get(&k).unwrap(), Lookup::Miss));
        assert!(!store.contains(&k).unwrap());
        let put_hash = store.put(&k, &bytes).unwrap();
        assert_eq!(put_hash, ContentHash::of(&bytes));
        assert!(store.contains(&k).unwrap());
        let (got, got_hash) = expect_hit(store.get(&k).unwrap());
        assert_eq!(got, bytes);
        assert_eq!(got_hash, put_hash);
        assert_eq!(store.peek_hash(&k), Some(put_hash));
    }
}

#[test]
fn entries_live_under_sharded_hex_paths() {
    let (dir, store) = store();
    let k = key(1);
    store.put(&k, b"x").unwrap();
    let hex = k.to_string();
    let expected = dir.path().join("objects").join(&hex[..2]).join(&hex);
    assert_eq!(store.entry_path(&k), expected);
    let bytes = fs::read(expected).unwrap();
    assert_eq!(&bytes[..4], b"LBC1");
    assert_eq!(bytes.len(), 48 + 1);
}

#[test]
fn truncated_entry_is_corrupt_then_absent() {
    let (_dir, store) = store();
    let k = key(1);
    store.put(&k, &payload(5000, 3)).unwrap();
    let path = store.entry_path(&k);
    let len = fs::metadata(&path).unwrap().len();
    OpenOptions::new()
        .write(true)
        .open(&path)
        .unwrap()
        .set_len(len - 1)
        .unwrap();

    let reason = expect_corrupt(store.get(&k).unwrap());
    assert_eq!(
        reason,
        Corruption::Truncated {
            expected: len,
            found: len - 1
        }
    );
    assert!(!path.exists(), "a corrupt entry is deleted");
    assert!(matches!(store.get(&k).unwrap(), Lookup::Miss));
}

#[test]
fn one_flipped_payload_byte_is_corrupt() {
    let (_dir, store) = store();
    let k = key(1);
    store.put(&k, &payload(5000, 3)).unwrap();
    let path = store.entry_path(&k);
    let mut bytes = fs::read(&path).unwrap();
    bytes[48 + 2500] ^= 0x01;
    fs::write(&path, bytes).unwrap();

    assert_eq!(
        expect_corrupt(store.get(&k).unwrap()),
        Corruption::HashMismatch
    );
    assert!(matches!(store.get(&k).unwrap(), Lookup::Miss));
}

#[test]
fn foreign_files_are_corrupt_not_panics_or_huge_allocations() {
    let (_dir, store) = store();
    let k = key(1);
    let path = store.entry_path(&k);
    fs::create_dir_all(path.parent().unwrap()).unwrap();

    let mut huge_claim = Vec::from(*b"LBC1");
    huge_claim.extend(1u32.to_le_bytes());
    huge_claim.extend(u64::MAX.to_le_bytes());
    huge_claim.extend([0u8; 32]);
    let mut future = huge_claim.clone();
    future[4..8].copy_from_slice(&2u32.to_le_bytes());
    let mut trailing = Vec::from(*b"LBC1");
    trailing.extend(1u32.to_le_bytes());
    trailing.extend(0u64.to_le_bytes());
    trailing.extend(blake3::hash(b"").as_bytes());
    trailing.push(0);

    let cases: [(&[u8], Corruption); 5] = [
        (
            b"",
            Corruption::Truncated {
                expected: 48,
                found: 0,
            },
        ),
        (&[b'x'; 100], Corruption::BadMagic),
        (&future, Corruption::UnknownFormat { found: 2 }),
        (
            &huge_claim,
            Corruption::Truncated {
                expected: u64::MAX,
                found: 48,
            },
        ),
        (
            &trailing,
            Corruption::TrailingData {
                expected: 48,
                found: 49,
            },
        ),
    ];
    for (content, expected) in cases {
        fs::write(&path, content).unwrap();
        assert_eq!(store.peek_hash(&k), None);
        assert_eq!(expect_corrupt(store.get(&k).unwrap()), expected);
        assert!(matches!(store.get(&k).unwrap(), Lookup::Miss));
    }
}

#[test]
fn stray_temp_files_do_not_confuse_get() {
    let (_dir, store) = store();
    let k = key(1);
    let shard = store.entry_path(&k).parent().unwrap().to_path_buf();
    fs::create_dir_all(&shard).unwrap();
    // A half-written temp file such as a crash leaves behind, with a valid-looking header.
    fs::write(
        shard.join(".tmp-1-0-00000000deadbeef"),
        b"LBC1\x01\0\0\0garbage",
    )
    .unwrap();
    assert!(matches!(store.get(&k).unwrap(), Lookup::Miss));
    assert!(!store.contains(&k).unwrap());
    store.put(&k, b"real").unwrap();
    assert_eq!(expect_hit(store.get(&k).unwrap()).0, b"real");
}

#[test]
fn put_leaves_no_temp_files_behind() {
    let (_dir, store) = store();
    let k = key(1);
    for _ in 0..3 {
        store.put(&k, b"again").unwrap();
    }
    let shard = store.entry_path(&k).parent().unwrap().to_path_buf();
    let names: Vec<String> = fs::read_dir(shard)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(names, [k.to_string()]);
}

#[test]
fn remove_reports_whether_there_was_an_entry() {
    let (_dir, store) = store();
    let k = key(1);
    assert!(!store.remove(&k).unwrap());
    store.put(&k, b"x").unwrap();
    assert!(store.remove(&k).unwrap());
    assert!(matches!(store.get(&k).unwrap(), Lookup::Miss));
}

#[test]
fn concurrent_writers_of_one_key_never_expose_a_partial_entry() {
    let (_dir, store) = store();
    let store = Arc::new(store);
    let k = key(1);
    // Large enough that a write spans many syscalls, so a torn read would be likely if possible.
    let bytes = Arc::new(payload(300_000, 9));
    let expected_hash = ContentHash::of(&bytes);
    let writers_done = Arc::new(AtomicUsize::new(0));

    let writers: Vec<_> = (0..2)
        .map(|_| {
            let (store, bytes, done) = (store.clone(), bytes.clone(), writers_done.clone());
            thread::spawn(move || {
                for _ in 0..50 {
                    assert_eq!(store.put(&k, &bytes).unwrap(), expected_hash);
                }
                done.fetch_add(1, Ordering::SeqCst);
            })
        })
        .collect();
    let reader = {
        let (store, bytes, done) = (store.clone(), bytes.clone(), writers_done.clone());
        thread::spawn(move || {
            let mut hits = 0;
            loop {
                // Read the flag before the lookup, so the final lookup starts after both
                // writers have finished and must be a hit.
                let finished = done.load(Ordering::SeqCst) == 2;
                let hit = match store.get(&k).unwrap() {
                    Lookup::Hit { payload, hash } => {
                        // `assert!`, not `assert_eq!`: don't print 300 kB on failure.
                        assert!(payload == *bytes, "a hit returned different bytes");
                        assert_eq!(hash, expected_hash);
                        true
                    }
                    Lookup::Miss => false,
                    Lookup::Corrupt { reason } => panic!("reader saw a partial entry: {reason}"),
                };
                hits += usize::from(hit);
                if finished {
                    assert!(hit, "the entry is missing after both writers finished");
                    return hits;
                }
            }
        })
    };
    for w in writers {
        w.join().unwrap();
    }
    let hits = reader.join().unwrap();
    assert!(hits >= 1);
}

#[test]
fn store_is_object_safe() {
    let (_dir, local) = store();
    let store: Box<dyn Store> = Box::new(local);
    let k = key(1);
    store.put(&k, b"via the trait").unwrap();
    assert_eq!(expect_hit(store.get(&k).unwrap()).0, b"via the trait");
}

#[test]
fn a_streamed_entry_is_the_entry_put_would_write() {
    let (_dir, store) = store();
    let data = payload(3 << 20, 7);
    let mut pending = store.begin(&key(1)).unwrap();
    // Uneven pieces, some larger than the write buffer.
    for piece in data.chunks(1_234_567) {
        std::io::Write::write_all(&mut pending, piece).unwrap();
    }
    let hash = pending.commit().unwrap();
    assert_eq!(hash, ContentHash::of(&data));
    let streamed = fs::read(store.entry_path(&key(1))).unwrap();
    store.put(&key(2), &data).unwrap();
    assert_eq!(streamed, fs::read(store.entry_path(&key(2))).unwrap());
    assert_eq!(
        expect_hit(store.get(&key(1)).unwrap()),
        (data.clone(), hash)
    );

    let crate::cache::Opened::Entry(reader) = store.open(&key(1)).unwrap() else {
        panic!("expected an entry");
    };
    assert_eq!((reader.len(), reader.hash()), (data.len() as u64, hash));
    let mut buf = vec![0u8; 1000];
    reader.read_at(2_000_000, &mut buf).unwrap();
    assert_eq!(buf, data[2_000_000..2_001_000]);
    let end = data.len() as u64 - 999;
    assert!(reader.read_at(end, &mut buf).is_err(), "past the payload");
    assert!(
        reader.read_at(u64::MAX - 10, &mut buf).is_err(),
        "overflowing offset"
    );
}

#[test]
fn an_uncommitted_stream_leaves_nothing() {
    let (dir, store) = store();
    let mut pending = store.begin(&key(1)).unwrap();
    std::io::Write::write_all(&mut pending, &payload(5000, 1)).unwrap();
    drop(pending);
    assert!(matches!(store.get(&key(1)).unwrap(), Lookup::Miss));
    let shard = store.entry_path(&key(1));
    let left = fs::read_dir(shard.parent().unwrap()).unwrap().count();
    assert_eq!(left, 0, "temp file left in {}", dir.path().display());
}

#[test]
fn opening_a_truncated_entry_is_corrupt_and_removes_it() {
    let (_dir, store) = store();
    store.put(&key(1), &payload(10_000, 3)).unwrap();
    let path = store.entry_path(&key(1));
    let file = OpenOptions::new().write(true).open(&path).unwrap();
    file.set_len(5_000).unwrap();
    drop(file);
    assert!(matches!(
        store.open(&key(1)).unwrap(),
        crate::cache::Opened::Corrupt(Corruption::Truncated { .. })
    ));
    assert!(!path.exists());
    assert!(matches!(
        store.open(&key(1)).unwrap(),
        crate::cache::Opened::Miss
    ));
}

#[test]
fn a_self_verified_entry_keeps_its_declared_hash_and_is_never_read_whole() {
    let (_dir, store) = store();
    let data = payload(5 << 20, 9);
    let declared = ContentHash::of(b"what the payload's own trailer hashes to");
    let mut pending = store.begin_self_verified(&key(1)).unwrap();
    std::io::Write::write_all(&mut pending, &data).unwrap();
    assert_eq!(pending.commit_declared(declared).unwrap(), declared);
    assert_eq!(store.peek_hash(&key(1)), Some(declared));

    let crate::cache::Opened::Entry(reader) = store.open(&key(1)).unwrap() else {
        panic!("expected an entry");
    };
    assert!(reader.self_verified());
    assert_eq!((reader.len(), reader.hash()), (data.len() as u64, declared));
    let mut buf = vec![0u8; 4096];
    reader.read_at(4 << 20, &mut buf).unwrap();
    assert_eq!(buf, data[4 << 20..(4 << 20) + 4096]);
    drop(reader);
    // `get` cannot check a declared hash, so it never serves the payload as verified.
    assert_eq!(
        expect_corrupt(store.get(&key(1)).unwrap()),
        Corruption::SelfVerified
    );

    // An ordinary entry is not self-verified, and the two commits do not mix.
    store.put(&key(2), &data).unwrap();
    let crate::cache::Opened::Entry(reader) = store.open(&key(2)).unwrap() else {
        panic!("expected an entry");
    };
    assert!(!reader.self_verified());
    assert!(
        store
            .begin(&key(3))
            .unwrap()
            .commit_declared(declared)
            .is_err()
    );
    assert!(
        store
            .begin_self_verified(&key(4))
            .unwrap()
            .commit()
            .is_err()
    );
    assert!(matches!(store.get(&key(3)).unwrap(), Lookup::Miss));
    assert!(matches!(store.get(&key(4)).unwrap(), Lookup::Miss));
}
