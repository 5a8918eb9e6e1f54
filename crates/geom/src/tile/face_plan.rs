//! Welding across a scaffold face by structure rather than by name, for a cell that is the same
//! in every element (a uniform local mesh): most shared vertices lie inside one face, where
//! the two elements sharing it see the same points through different corner orders.
//!
//! A face's corners, ranked by their global node ids, give every element the same frame for
//! that face: a vertex's weights rewritten over corner *ranks* instead of global ids is a key
//! that both sides compute alike, exactly when their names (module docs of [`super::weld`])
//! are equal. So for each local face and each rank order of its corners, the face's vertices
//! sorted by rank key form a list; when the two sides' lists are equal (checked once per pair
//! of list classes, not per element), the k-th vertex of one side is the k-th of the other.
//!
//! Invariants: a plan pairs slot `s` of one element with slot `s'` of its neighbour only if
//! the name weld would give them equal names; faces whose lists differ, hold repeated keys, or
//! whose corners repeat a node are not planned (the caller names their vertices instead), so
//! the weld's result is the same whichever path a vertex takes.

use std::collections::HashMap;

use super::lattice::Weights;

/// No face: the slot lies on an element edge or node (or is used by caps only).
pub const NO_FACE: u8 = u8::MAX;

/// A slot's key in a face's rank frame: its ends' `(rank, weight)` lists, the smaller first,
/// and whether it is a band's upper level's crossing.
type RankKey = (Vec<(u8, u32)>, Vec<(u8, u32)>, bool);

/// The vertices of one face in one rank order of its corners.
struct RankTable {
    /// Which distinct sorted key list this table has: equal ids, equal lists.
    class: u32,
    /// The face's slots sorted by rank key.
    order: Vec<u32>,
    /// Per slot of the face (by its index on the face): its place in `order`.
    place: Vec<u32>,
}

/// The structural weld plan of one uniform local mesh.
pub struct FacePlan {
    /// Per shared slot: the face whose interior it lies in, or [`NO_FACE`].
    face_of: Vec<u8>,
    /// Per shared slot on a face: its index among that face's slots.
    index_on_face: Vec<u32>,
    /// Per face: its corners (element-local), ascending.
    face_corners: Vec<Vec<u8>>,
    /// Per face and rank code ([`FacePlan::code`]): the table, when that order is plannable.
    tables: Vec<Option<RankTable>>,
    codes: usize,
}

impl FacePlan {
    /// The plan for shared vertices with weights `ends` (`a`, optional `b`, and whether it is
    /// a band's upper level's crossing) used by surface triangles (`surface`); `face_masks`
    /// are the element's faces.
    pub fn new(
        ends: &[(Weights, Option<Weights>, bool)],
        surface: &[bool],
        face_masks: &[u8],
    ) -> FacePlan {
        let face_corners: Vec<Vec<u8>> = face_masks
            .iter()
            .map(|&m| (0..8u8).filter(|c| m & 1 << c != 0).collect())
            .collect();
        let corners_per_face = face_corners.iter().map(Vec::len).max().unwrap_or(0);
        let codes = corners_per_face.pow(corners_per_face as u32);
        let mut face_of = vec![NO_FACE; ends.len()];
        let mut index_on_face = vec![0u32; ends.len()];
        let mut face_slots: Vec<Vec<u32>> = vec![Vec::new(); face_masks.len()];
        for (s, (a, b, _)) in ends.iter().enumerate() {
            let mask = a.mask() | b.map_or(0, |b| b.mask());
            let mut containing = face_masks
                .iter()
                .enumerate()
                .filter(|&(_, &f)| mask & !f == 0);
            if let (Some((f, _)), None) = (containing.next(), containing.next())
                && surface[s]
            {
                face_of[s] = f as u8;
                index_on_face[s] = face_slots[f].len() as u32;
                face_slots[f].push(s as u32);
            }
        }
        let mut classes: HashMap<Vec<RankKey>, u32> = HashMap::new();
        let mut tables = Vec::with_capacity(face_masks.len() * codes);
        for (f, corners) in face_corners.iter().enumerate() {
            for code in 0..codes {
                let Some(rank) = ranks_of_code(code, corners.len()) else {
                    tables.push(None);
                    continue;
                };
                let rank_of = |c: u8| rank[corners.iter().position(|&x| x == c).unwrap_or(0)];
                let key = |s: u32| -> RankKey {
                    let list = |w: &Weights| {
                        let mut l: Vec<(u8, u32)> =
                            w.as_slice().iter().map(|&(c, x)| (rank_of(c), x)).collect();
                        l.sort_unstable();
                        l
                    };
                    let (a, b, upper) = &ends[s as usize];
                    let (a, b) = (list(a), b.as_ref().map(list).unwrap_or_default());
                    if b.is_empty() || a <= b {
                        (a, b, *upper)
                    } else {
                        (b, a, *upper)
                    }
                };
                let mut keyed: Vec<(RankKey, u32)> =
                    face_slots[f].iter().map(|&s| (key(s), s)).collect();
                keyed.sort_unstable();
                if keyed.windows(2).any(|w| w[0].0 == w[1].0) {
                    tables.push(None);
                    continue;
                }
                let order: Vec<u32> = keyed.iter().map(|&(_, s)| s).collect();
                let mut place = vec![0u32; order.len()];
                for (k, &s) in order.iter().enumerate() {
                    place[index_on_face[s as usize] as usize] = k as u32;
                }
                let next = classes.len() as u32;
                let class = *classes
                    .entry(keyed.into_iter().map(|(k, _)| k).collect())
                    .or_insert(next);
                tables.push(Some(RankTable {
                    class,
                    order,
                    place,
                }));
            }
        }
        FacePlan {
            face_of,
            index_on_face,
            face_corners,
            tables,
            codes,
        }
    }

    /// The face whose interior shared slot `s` lies in, or [`NO_FACE`].
    #[inline]
    pub fn face_of(&self, s: usize) -> u8 {
        self.face_of[s]
    }

    /// The rank code of face `f` of an element with corner nodes `corners`: corner `j` of the
    /// face has rank `r_j` (how many of the face's nodes are smaller), and the code is
    /// `Σ r_j kʲ`. A face that repeats a node gives a code with no table.
    #[inline]
    pub fn code(&self, f: usize, corners: &[u32]) -> usize {
        let on_face = &self.face_corners[f];
        let k = on_face.len();
        let mut code = 0;
        for &c in on_face.iter().rev() {
            let g = corners[c as usize];
            let rank = on_face.iter().filter(|&&o| corners[o as usize] < g).count();
            code = code * k + rank;
        }
        code
    }

    fn table(&self, f: usize, code: usize) -> Option<&RankTable> {
        self.tables.get(f * self.codes + code)?.as_ref()
    }

    /// Whether face `f` seen with rank code `code` pairs slot by slot with face `g` seen with
    /// `other` (the neighbour's view of the same scaffold face).
    #[inline]
    pub fn pairs(&self, f: usize, code: usize, g: usize, other: usize) -> bool {
        match (self.table(f, code), self.table(g, other)) {
            (Some(a), Some(b)) => a.class == b.class,
            _ => false,
        }
    }

    /// The neighbour's slot matching slot `s` (on face `f`, rank code `code`), the neighbour
    /// seeing the face as `g` with rank code `other`; only after [`FacePlan::pairs`] said yes.
    #[inline]
    pub fn partner(&self, s: usize, f: usize, code: usize, g: usize, other: usize) -> u32 {
        let (Some(mine), Some(theirs)) = (self.table(f, code), self.table(g, other)) else {
            return u32::MAX;
        };
        let k = mine.place[self.index_on_face[s] as usize];
        theirs.order[k as usize]
    }
}

/// The ranks a code of `k` corners stands for, when they are a permutation of `0..k`.
fn ranks_of_code(mut code: usize, k: usize) -> Option<Vec<u8>> {
    let mut ranks = Vec::with_capacity(k);
    for _ in 0..k {
        ranks.push((code % k) as u8);
        code /= k;
    }
    let mut seen = 0u32;
    for &r in &ranks {
        seen |= 1 << r;
    }
    (seen.count_ones() as usize == k).then_some(ranks)
}
