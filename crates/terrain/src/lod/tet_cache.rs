//! A cache of chunk tetrahedra by configuration: a chunk's tets, moved by a translation that
//! keeps every level's lattice, are the tets of a chunk whose surroundings are moved the same
//! way. A viewer's level map repeats the same few hundred surroundings along its path, so a
//! chunk beside a finer level (the window path of [`super::mesh`], about 50 ms for a 16^3
//! chunk) is built once per surrounding and then copied.
//!
//! ```text
//!   key(K) = ( K's level,
//!              the leaves meeting K's box +- (window margin + one coarsest cell)
//!                  [everything the window's forest reads; the fast path reads less],
//!                  each as (level, lower corner - K's lower corner),
//!              the world box clipped to K's box +- (window margin + two coarsest cells),
//!                  minus K's lower corner [the roots the forest starts from, the domain] )
//!   cacheable:  K's lower corner a multiple of the coarsest cell on every axis
//!               (so the translation maps every level's lattice, corners and centres, to itself)
//!   hit:        decode the entry at K's lower corner (no sort: a translation keeps the
//!               lexicographic order of the sorted tets)
//!   miss:       chunk_tets, encode relative to K's lower corner, keep it while the byte budget
//!               allows (first come, first kept), return the tets
//!   encoded_tets: the same lookup, answering with the encoding (any chunk's, kept or not):
//!               equal encodings at one corner are equal tets, which is how the world finds
//!               that a chunk the map change marked keeps its tets
//!   entry:      one u32 per tet, in the tets' order:
//!                 bit 31 = 0: a body-centred tet of level k (bit 30 = 0) or k - 1 (bit 30 = 1),
//!                             template j (bits 26-29, canonical bcc_tet(level, 0, j / 4, j % 4))
//!                             moved by cell (x, y, z) of its level, each + 4 in 8 bits
//!                 bit 31 = 1: index of an explicit tet (green tets, anything else)
//! ```
//!
//! Why a hit is exact: the window's forest, closure and green templates are built from integer
//! comparisons (lexicographic orders, squared lengths, signs of volumes) and midpoints, all kept
//! by a translation; the map is read only through the leaves in the key's region, and the roots
//! and the domain only through the world box in it. The tests compare every chunk through the
//! cache with [`chunk_tets`] over many maps, and every entry is decoded and compared with the
//! tets it was made from before it is kept.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use super::error::LodError;
use super::lattice::{bcc_tet, canonical, cell_size, Tet};
use super::level_map::{ChunkKey, LevelMap};
use super::mesh::{chunk_tets, window_margin, MeshTet};
use super::refine::TetKind;

/// The default byte budget of a [`TetCache`]: 1 GiB.
pub const DEFAULT_TET_CACHE_BYTES: usize = 1 << 30;

const SPECIAL: u32 = 1 << 31;
const FINER: u32 = 1 << 30;
const BIAS: i32 = 4;

/// What a [`TetCache`] holds and did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TetCacheStats {
    /// Surroundings kept.
    pub entries: usize,
    /// Their bytes: the entries' tets and the keys' leaves.
    pub bytes: usize,
    /// Chunks answered from the cache.
    pub hits: u64,
    /// Chunks built (not cacheable, or not yet kept).
    pub misses: u64,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct Key {
    level: u8,
    leaves: Vec<(u8, [i64; 3])>,
    world: [i64; 6],
}

impl Key {
    /// Its heap bytes, counted in the budget with its entry's.
    fn bytes(&self) -> usize {
        self.leaves.len() * std::mem::size_of::<(u8, [i64; 3])>()
    }
}

#[derive(Debug, PartialEq, Eq)]
struct Entry {
    codes: Vec<u32>,
    specials: Vec<MeshTet>,
}

/// A chunk's tets in the cache's encoding, relative to the chunk's lower corner
/// ([`TetCache::encoded_tets`]). Equal values decode to the same tets: a chunk whose
/// `EncodedTets` is the same under two maps has the same tets under both, and so the same
/// surface while the field does not change.
#[derive(Clone, Debug)]
pub struct EncodedTets {
    level: u8,
    origin: [i32; 3],
    entry: Arc<Entry>,
}

impl PartialEq for EncodedTets {
    fn eq(&self, other: &Self) -> bool {
        self.level == other.level
            && self.origin == other.origin
            && (Arc::ptr_eq(&self.entry, &other.entry) || self.entry == other.entry)
    }
}

impl EncodedTets {
    /// The tets.
    pub fn tets(&self) -> Vec<MeshTet> {
        decode(&self.entry, self.level, self.origin)
    }

    /// Bytes of the encoding (shared with the cache when the cache keeps it).
    pub fn bytes(&self) -> usize {
        self.entry.bytes()
    }
}

/// A chunk's tets from [`TetCache::encoded_tets`]: encoded when they can be, and the tets
/// themselves when they were built rather than found.
#[derive(Debug)]
pub struct ChunkTets {
    /// The encoding, checked to decode to the tets (`None`: they have no encoding).
    pub encoded: Option<EncodedTets>,
    built: Option<Vec<MeshTet>>,
}

impl ChunkTets {
    /// The tets, sorted ([`chunk_tets`]).
    pub fn into_tets(self) -> Vec<MeshTet> {
        match (self.built, self.encoded) {
            (Some(t), _) => t,
            (None, Some(e)) => e.tets(),
            (None, None) => Vec::new(),
        }
    }
}

impl Entry {
    fn bytes(&self) -> usize {
        self.codes.len() * 4 + self.specials.len() * std::mem::size_of::<MeshTet>()
    }
}

struct Inner {
    map: HashMap<Key, Arc<Entry>>,
    bytes: usize,
    hits: u64,
    misses: u64,
}

/// Chunk tetrahedra by surroundings, shared by the threads of a world (see the module doc).
pub struct TetCache {
    budget: usize,
    inner: Mutex<Inner>,
}

impl std::fmt::Debug for TetCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TetCache")
            .field("budget", &self.budget)
            .field("stats", &self.stats())
            .finish()
    }
}

/// The canonical body-centred tets of cell 0 of `level`, in template order.
fn templates(level: u8) -> [Tet; 12] {
    std::array::from_fn(|j| canonical(bcc_tet(level, [0; 3], j / 4, j % 4)))
}

fn moved(t: &Tet, d: [i32; 3]) -> Tet {
    t.map(|p| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
}

impl TetCache {
    /// An empty cache that keeps at most `budget` bytes of entries (0 keeps none).
    pub fn new(budget: usize) -> Self {
        TetCache {
            budget,
            inner: Mutex::new(Inner {
                map: HashMap::new(),
                bytes: 0,
                hits: 0,
                misses: 0,
            }),
        }
    }

    /// Entries, bytes, hits and misses so far.
    pub fn stats(&self) -> TetCacheStats {
        match self.inner.lock() {
            Ok(g) => TetCacheStats {
                entries: g.map.len(),
                bytes: g.bytes,
                hits: g.hits,
                misses: g.misses,
            },
            Err(_) => TetCacheStats::default(),
        }
    }

    /// Forgets every entry (the counters stay).
    pub fn clear(&self) {
        if let Ok(mut g) = self.inner.lock() {
            g.map.clear();
            g.bytes = 0;
        }
    }

    /// [`chunk_tets`] of `chunk`, from the cache when a chunk with the same surroundings was
    /// built before: the same tets, in the same order.
    pub fn chunk_tets(&self, map: &LevelMap, chunk: &ChunkKey) -> Result<Vec<MeshTet>, LodError> {
        Ok(self.encoded_tets(map, chunk)?.into_tets())
    }

    /// [`TetCache::chunk_tets`] with the tets' encoding at the chunk's lower corner: the
    /// cache's entry on a hit (nothing decoded yet); otherwise the tets are built, encoded and
    /// the encoding checked to decode to them, whether or not the cache keeps it.
    pub fn encoded_tets(&self, map: &LevelMap, chunk: &ChunkKey) -> Result<ChunkTets, LodError> {
        if !map.contains(chunk) {
            return chunk_tets(map, chunk).map(|t| ChunkTets {
                encoded: None,
                built: Some(t),
            });
        }
        let level = chunk.level;
        let (lo, _) = chunk.bounds(map.geometry());
        let origin = to_point(lo);
        let key = origin.and_then(|_| key(map, chunk));
        match (&key, origin) {
            (Some(key), Some(origin)) => {
                // One lock: the lookup and its count.
                let found = self.inner.lock().ok().and_then(|mut g| {
                    let e = g.map.get(key).cloned();
                    match e {
                        Some(_) => g.hits += 1,
                        None => g.misses += 1,
                    }
                    e
                });
                if let Some(entry) = found {
                    return Ok(ChunkTets {
                        encoded: Some(EncodedTets {
                            level,
                            origin,
                            entry,
                        }),
                        built: None,
                    });
                }
            }
            _ => self.count_miss(),
        }
        let tets = chunk_tets(map, chunk)?;
        let encoded = origin.and_then(|o| {
            let e = encode(&tets, level, o)?;
            // Only an encoding that gives back exactly what it was made from is used.
            (decode(&e, level, o) == tets).then(|| EncodedTets {
                level,
                origin: o,
                entry: Arc::new(e),
            })
        });
        if let (Some(key), Some(e), true) = (key, &encoded, self.budget > 0) {
            if let Ok(mut g) = self.inner.lock() {
                let b = e.entry.bytes() + key.bytes();
                if g.bytes + b <= self.budget && !g.map.contains_key(&key) {
                    g.bytes += b;
                    g.map.insert(key, Arc::clone(&e.entry));
                }
            }
        }
        Ok(ChunkTets {
            encoded,
            built: Some(tets),
        })
    }

    fn count_miss(&self) {
        if let Ok(mut g) = self.inner.lock() {
            g.misses += 1;
        }
    }
}

fn to_point(v: [i64; 3]) -> Option<[i32; 3]> {
    let p = [
        i32::try_from(v[0]).ok()?,
        i32::try_from(v[1]).ok()?,
        i32::try_from(v[2]).ok()?,
    ];
    Some(p)
}

/// The surroundings of `chunk` (a leaf of `map`), or `None` when its lower corner is not on
/// the coarsest lattice.
fn key(map: &LevelMap, chunk: &ChunkKey) -> Option<Key> {
    let g = map.geometry();
    let s_top = cell_size(g.levels);
    let (lo, hi) = chunk.bounds(g);
    if lo.iter().any(|v| v.rem_euclid(s_top) != 0) {
        return None;
    }
    let m = window_margin(map, chunk.level);
    let r = m + s_top;
    let leaves = map
        .leaves_touching(lo.map(|v| v - r), hi.map(|v| v + r))
        .into_iter()
        .map(|n| {
            let (a, _) = n.bounds(g);
            (n.level, [a[0] - lo[0], a[1] - lo[1], a[2] - lo[2]])
        })
        .collect();
    let w = g.world_size();
    let rw = m + 2 * s_top;
    let mut world = [0i64; 6];
    for i in 0..3 {
        world[2 * i] = (lo[i] - rw).max(0) - lo[i];
        world[2 * i + 1] = (hi[i] + rw).min(w[i]) - lo[i];
    }
    Some(Key {
        level: chunk.level,
        leaves,
        world,
    })
}

/// `tets` relative to `origin`; `None` when one cannot be written (it is then not kept).
fn encode(tets: &[MeshTet], level: u8, origin: [i32; 3]) -> Option<Entry> {
    let own = templates(level);
    let finer = (level > 0).then(|| templates(level - 1));
    let mut codes = Vec::with_capacity(tets.len());
    let mut specials = Vec::new();
    let neg = origin.map(|v| -v);
    for t in tets {
        let rel = moved(&t.tet, neg);
        let code = if t.kind == TetKind::Bcc {
            let (set, bit) = if t.level == level {
                (Some(&own), 0)
            } else if level > 0 && t.level + 1 == level {
                (finer.as_ref(), FINER)
            } else {
                (None, 0)
            };
            set.and_then(|ts| lattice_code(&rel, ts, cell_size(t.level) as i32))
                .map(|c| c | bit)
        } else {
            None
        };
        match code {
            Some(c) => codes.push(c),
            None => {
                let i = u32::try_from(specials.len())
                    .ok()
                    .filter(|&i| i < SPECIAL)?;
                codes.push(SPECIAL | i);
                specials.push(MeshTet { tet: rel, ..*t });
            }
        }
    }
    Some(Entry { codes, specials })
}

/// The code of `rel` as a template of `ts` moved by a whole cell of edge `cs`.
fn lattice_code(rel: &Tet, ts: &[Tet; 12], cs: i32) -> Option<u32> {
    for (j, t0) in ts.iter().enumerate() {
        let d: [i32; 3] = std::array::from_fn(|i| rel[0][i] - t0[0][i]);
        if d.iter().any(|v| v % cs != 0) || moved(t0, d) != *rel {
            continue;
        }
        let c: [i32; 3] = std::array::from_fn(|i| d[i] / cs + BIAS);
        if c.iter().any(|v| !(0..256).contains(v)) {
            return None;
        }
        return Some((j as u32) << 26 | (c[0] as u32) << 16 | (c[1] as u32) << 8 | c[2] as u32);
    }
    None
}

fn decode(e: &Entry, level: u8, origin: [i32; 3]) -> Vec<MeshTet> {
    let own = templates(level);
    let finer = templates(level.saturating_sub(1));
    let (cs_own, cs_finer) = (
        cell_size(level) as i32,
        cell_size(level.saturating_sub(1)) as i32,
    );
    e.codes
        .iter()
        .map(|&code| {
            if code & SPECIAL != 0 {
                let t = e.specials[(code & !SPECIAL) as usize];
                return MeshTet {
                    tet: moved(&t.tet, origin),
                    ..t
                };
            }
            let (ts, cs, l) = if code & FINER != 0 {
                (&finer, cs_finer, level.saturating_sub(1))
            } else {
                (&own, cs_own, level)
            };
            let j = (code >> 26 & 15) as usize;
            let c = [code >> 16 & 255, code >> 8 & 255, code & 255].map(|v| v as i32 - BIAS);
            let d: [i32; 3] = std::array::from_fn(|i| c[i] * cs + origin[i]);
            MeshTet {
                tet: moved(&ts[j], d),
                level: l,
                kind: TetKind::Bcc,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::super::level_map::LodGeometry;
    use super::*;

    fn viewer_maps(g: LodGeometry, n: usize) -> Vec<LevelMap> {
        let w = g.world_size();
        (0..n)
            .map(|k| {
                let t = k as f64 / n as f64;
                let p = [
                    0.1 * w[0] as f64 + 0.8 * t * w[0] as f64,
                    0.5 * w[1] as f64,
                    0.15 * w[2] as f64 + 0.7 * t * w[2] as f64,
                ];
                LevelMap::from_viewer(g, p, 1.5)
            })
            .collect()
    }

    /// Through the cache, every chunk of many maps gets exactly [`chunk_tets`]; most of them
    /// are hits, so the translations are checked, not only the encoding.
    #[test]
    fn cached_tets_equal_built_tets() {
        // Chunks below and from LOCAL_CHUNK cells (their dependency boxes differ).
        for (g, maps) in [
            (LodGeometry::new(2, 4, [2, 1, 2]).unwrap(), 12),
            (LodGeometry::new(1, 8, [4, 2, 4]).unwrap(), 12),
        ] {
            let cache = TetCache::new(DEFAULT_TET_CACHE_BYTES);
            let mut all: Vec<LevelMap> = viewer_maps(g, maps);
            all.extend((0..4).map(|s| LevelMap::random(g, s, 0.4)));
            for map in &all {
                for c in map.chunks() {
                    let direct = chunk_tets(map, c).unwrap();
                    let cached = cache.chunk_tets(map, c).unwrap();
                    assert!(cached == direct, "chunk {c:?} differs through the cache");
                }
            }
            let s = cache.stats();
            eprintln!("{g:?}: {s:?}");
            assert!(2 * s.hits > s.misses, "{s:?}: the maps repeat surroundings");
            assert!(s.entries > 0 && s.bytes > 0);
        }
    }

    #[test]
    fn a_zero_budget_keeps_nothing_and_answers_the_same() {
        let g = LodGeometry::new(1, 4, [4, 2, 4]).unwrap();
        let cache = TetCache::new(0);
        for map in viewer_maps(g, 6) {
            for c in map.chunks() {
                assert_eq!(
                    cache.chunk_tets(&map, c).unwrap(),
                    chunk_tets(&map, c).unwrap()
                );
            }
        }
        let s = cache.stats();
        assert_eq!((s.entries, s.bytes, s.hits), (0, 0, 0));
    }

    #[test]
    fn every_template_moved_by_a_cell_round_trips() {
        for level in 0..3u8 {
            let ts = templates(level);
            let cs = cell_size(level) as i32;
            let origin = [64, 128, 32];
            let tets: Vec<MeshTet> = (0..12)
                .flat_map(|j| {
                    [[-1, 0, 2], [5, -4, 200]].map(move |c| MeshTet {
                        tet: moved(&ts[j], [c[0] * cs + 64, c[1] * cs + 128, c[2] * cs + 32]),
                        level,
                        kind: TetKind::Bcc,
                    })
                })
                .collect();
            let e = encode(&tets, level, origin).unwrap();
            assert!(e.specials.is_empty());
            assert_eq!(decode(&e, level, origin), tets);
        }
    }

    /// Equal encodings are equal tets, and unequal tets unequal encodings, with and without
    /// the cache keeping them.
    #[test]
    fn encodings_compare_as_their_tets() {
        let g = LodGeometry::new(1, 8, [4, 2, 4]).unwrap();
        let maps = viewer_maps(g, 8);
        for budget in [0, DEFAULT_TET_CACHE_BYTES] {
            let cache = TetCache::new(budget);
            let (mut same, mut differ) = (0, 0);
            for (a, b) in maps.iter().zip(maps.iter().skip(1)) {
                for c in b.chunks().iter().filter(|c| a.contains(c)) {
                    let ea = cache.encoded_tets(a, c).unwrap().encoded.unwrap();
                    let eb = cache.encoded_tets(b, c).unwrap().encoded.unwrap();
                    let equal_tets = chunk_tets(a, c).unwrap() == chunk_tets(b, c).unwrap();
                    assert_eq!(ea == eb, equal_tets, "chunk {c:?}");
                    assert_eq!(eb.tets(), chunk_tets(b, c).unwrap());
                    if equal_tets {
                        same += 1;
                    } else {
                        differ += 1;
                    }
                }
            }
            assert!(same > 0 && differ > 0, "{same} the same, {differ} differ");
        }
    }

    #[test]
    fn a_chunk_for_another_map_is_refused() {
        let g = LodGeometry::new(1, 4, [2, 2, 2]).unwrap();
        let map = LevelMap::uniform(g, 1);
        let child = ChunkKey {
            level: 0,
            at: [0, 0, 0],
        };
        assert!(TetCache::new(1 << 20).chunk_tets(&map, &child).is_err());
    }
}
