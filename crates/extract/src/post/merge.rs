//! Merging vertices of a triangle mesh without breaking it: the exact local check.
//!
//! Merging a connected set K of vertices into one new vertex v replaces the region R (the
//! triangles touching K) by a fan around v. The result is still a closed 2-manifold of the same
//! topology, with consistent orientation, exactly when
//!
//! 1. R is a disc: its Euler characteristic V - E + F is 1, every inner edge has two triangles
//!    traversed in opposite directions, and its boundary edges form one simple cycle that avoids K;
//! 2. the triangles with exactly one vertex in K, with that vertex replaced by v, are the cone over
//!    that boundary cycle: each one's far edge is a boundary edge of R, each boundary edge is used
//!    once (so no two new triangles coincide and every link edge has two triangles);
//! 3. (geometry) no new triangle flips against the triangle it replaces or becomes (near) flat
//!    (one that was already flat may stay flat, or open up facing like the region).
//!
//! Triangles with two or more vertices in K collapse and are dropped. This is the link condition of
//! edge contraction applied to the whole cluster at once (`rmt-spec.md`, "When merging keeps the
//! surface a manifold"). Edge collapse (post-processed clustering) and the welding before meshopt
//! use it; integrated clustering tests its groups in the quotient instead
//! ([`crate::mt::clustering::quotient`]).
//!
//! ```text
//!      u-----w            u-----w
//!     / \ K / \          / \   / \
//!    x---k1-k2-y   =>   x---- v ---y     (K = {k1, k2} merged into v)
//!     \ /   \ /          \   / \ /
//!      s-----t            s-----t
//! ```

/// Marks "no vertex" in member chains.
const NONE: u32 = u32::MAX;

/// A dropped triangle.
const DEAD: [u32; 3] = [NONE; 3];

/// Why a merge was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reject {
    /// The region around K is not a disc (or K touches its boundary, e.g. the box).
    NotADisc,
    /// The new fan would duplicate triangles or leave a link edge without two triangles.
    NotACone,
    /// A new triangle would flip or become flat.
    Flip,
}

/// Working memory of one check; one per thread when checks run in parallel.
pub struct Scratch {
    region: Vec<u32>,
    edges: Vec<(u32, u32)>,
    verts: Vec<u32>,
    boundary: Vec<(u32, u32)>,
    used: Vec<bool>,
    local: LocalIds,
    /// Local ids of the region's triangles, in region order (small-region check).
    tri_local: Vec<[u8; 3]>,
    /// Whether the last check ran on bit sets (then `tri_local` and `kmask` describe `region`).
    small: bool,
    /// Local ids of the merged vertices (small-region check).
    kmask: u64,
    /// Directed edges of the region by start vertex, by end vertex, and boundary edges by start
    /// vertex, as bit sets of local ids (small-region check; entry `a` is cleared when local id
    /// `a` is handed out, so nothing is cleared per check).
    out: [u64; SMALL],
    incoming: [u64; SMALL],
    bnd: [u64; SMALL],
}

impl Default for Scratch {
    fn default() -> Self {
        Self {
            region: Vec::new(),
            edges: Vec::new(),
            verts: Vec::new(),
            boundary: Vec::new(),
            used: Vec::new(),
            local: LocalIds::default(),
            tri_local: Vec::new(),
            small: false,
            kmask: 0,
            out: [0; SMALL],
            incoming: [0; SMALL],
            bnd: [0; SMALL],
        }
    }
}

/// Most regions have at most this many vertices: their check runs on bit sets.
const SMALL: usize = 64;

/// Slots of the small hash map from vertex ids to local ids (twice [`SMALL`]).
const SLOTS: usize = 128;

/// Local ids 0.. for the vertices of one region: an open-addressing map of [`SLOTS`] slots,
/// cleared slot by slot, so a check allocates nothing.
struct LocalIds {
    keys: [u32; SLOTS],
    vals: [u8; SLOTS],
    filled: Vec<u8>,
}

impl Default for LocalIds {
    fn default() -> Self {
        Self {
            keys: [NONE; SLOTS],
            vals: [0; SLOTS],
            filled: Vec::with_capacity(SMALL),
        }
    }
}

impl LocalIds {
    fn clear(&mut self) {
        for &s in &self.filled {
            self.keys[s as usize] = NONE;
        }
        self.filled.clear();
    }

    fn slot(&self, v: u32) -> usize {
        let mut s = (v.wrapping_mul(0x9E37_79B1) >> 25) as usize;
        while self.keys[s] != NONE && self.keys[s] != v {
            s = (s + 1) & (SLOTS - 1);
        }
        s
    }

    /// The local id of `v`, numbering it if new; `None` when the region has more than
    /// [`SMALL`] vertices.
    fn get_or_insert(&mut self, v: u32) -> Option<usize> {
        let s = self.slot(v);
        if self.keys[s] == v {
            return Some(self.vals[s] as usize);
        }
        let id = self.filled.len();
        if id >= SMALL {
            return None;
        }
        self.keys[s] = v;
        self.vals[s] = id as u8;
        self.filled.push(s as u8);
        Some(id)
    }

    fn get(&self, v: u32) -> Option<usize> {
        let s = self.slot(v);
        (self.keys[s] == v).then(|| self.vals[s] as usize)
    }
}

/// A triangle mesh prepared for merges, with buffers kept between extractions.
#[derive(Default)]
pub struct MergeBuffers {
    /// The triangles; a dropped one becomes [`DEAD`] (no separate liveness array).
    tris: Vec<[u32; 3]>,
    /// Incident triangles of each original vertex (CSR): `inc[inc_start[v]..inc_start[v + 1]]`.
    inc_start: Vec<u32>,
    inc: Vec<u32>,
    /// Members of a merged vertex: a chain from the vertex through `next_member`.
    next_member: Vec<u32>,
    /// The vertex an original vertex has been merged into (itself if none).
    rep: Vec<u32>,
    /// Working memory of [`MergeBuffers::merge`], boxed so that lending it out moves a pointer,
    /// not kilobytes of tables (and allocates nothing).
    scratch: Option<Box<Scratch>>,
}

impl MergeBuffers {
    /// Loads `vertex_count` vertices and the triangles `indices` (three per triangle).
    pub fn load(&mut self, vertex_count: usize, indices: &[u32]) {
        self.tris.clear();
        self.tris
            .extend(indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
        // `next_member` serves as the table's working memory first (no separate array).
        crate::incidence::incidence(
            vertex_count,
            indices,
            &mut self.inc_start,
            &mut self.inc,
            &mut self.next_member,
        );
        self.next_member.fill(NONE);
        self.rep.clear();
        self.rep.extend(0..vertex_count as u32);
    }

    /// Bytes held by the adjacency structures.
    pub fn bytes(&self) -> usize {
        self.tris.len() * 12
            + (self.inc_start.len() + self.inc.len() + self.next_member.len() + self.rep.len()) * 4
    }

    /// The vertex that original vertex `v` now belongs to.
    pub fn rep(&self, v: u32) -> u32 {
        self.rep[v as usize]
    }

    /// Number of original vertices merged into current vertex `v` (1 for an unmerged vertex):
    /// the length of its member chain (a few links; no per-vertex count is stored).
    #[cfg(test)]
    pub fn member_count(&self, v: u32) -> u32 {
        let mut n = 0;
        let mut m = v;
        while m != NONE {
            n += 1;
            m = self.next_member[m as usize];
        }
        n
    }

    /// Number of triangles loaded (alive or not): `t` in `0..triangle_count()`.
    #[cfg(test)]
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    #[inline]
    fn live(&self, t: u32) -> bool {
        self.tris[t as usize] != DEAD
    }

    /// Whether triangle `t` (original numbering) still exists.
    #[cfg(test)]
    pub fn is_alive(&self, t: usize) -> bool {
        self.tris[t] != DEAD
    }

    /// Current vertices of triangle `t` (meaningful while it is alive).
    #[cfg(test)]
    pub fn triangle(&self, t: usize) -> [u32; 3] {
        self.tris[t]
    }

    /// The live triangles, as current vertex ids, in their original order.
    pub fn live_triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.tris.iter().copied().filter(|t| *t != DEAD)
    }

    /// The live triangles touching current vertex `v`, as current vertex ids, into `out`
    /// (`ids` is working memory).
    pub fn triangles_around(&self, v: u32, ids: &mut Vec<u32>, out: &mut Vec<[u32; 3]>) {
        self.collect_region(&[v], ids);
        out.clear();
        out.extend(ids.iter().map(|&t| self.tris[t as usize]));
    }

    /// Collects the live triangles touching any vertex of `k` into `region`, sorted.
    fn collect_region(&self, k: &[u32], region: &mut Vec<u32>) {
        self.collect_region_with_repeats(k, region);
        region.sort_unstable();
        region.dedup();
    }

    /// The live triangles touching `k`, unsorted; a triangle with several vertices in `k`
    /// appears once per such vertex.
    fn collect_region_with_repeats(&self, k: &[u32], region: &mut Vec<u32>) {
        region.clear();
        for &c in k {
            let mut m = c;
            while m != NONE {
                let (a, b) = (
                    self.inc_start[m as usize] as usize,
                    self.inc_start[m as usize + 1] as usize,
                );
                region.extend(self.inc[a..b].iter().filter(|&&t| self.live(t)));
                m = self.next_member[m as usize];
            }
        }
    }

    /// Merges the current vertices `k` (at least two, connected through mesh edges) into `k[0]`,
    /// placed at `new_pos`. With `check`, refuses merges that would break the mesh (see the module
    /// doc) and leaves everything unchanged; without it, merges anyway (the dissertation's
    /// behaviour). Returns the number of triangles dropped.
    pub fn merge(
        &mut self,
        positions: &mut [[f32; 3]],
        k: &[u32],
        new_pos: [f32; 3],
        check: bool,
    ) -> Result<usize, Reject> {
        let mut scratch = self.scratch.take().unwrap_or_default();
        let result = if check {
            self.check(&mut scratch, positions, k, new_pos)
                .map(|()| self.apply(positions, k, new_pos, &mut scratch.region))
        } else {
            Ok(self.apply(positions, k, new_pos, &mut scratch.region))
        };
        self.scratch = Some(scratch);
        result
    }

    /// Chains every member of `k[1..]` behind `k[0]` and points their `rep` at it.
    fn chain_members(&mut self, k: &[u32]) {
        let v = k[0];
        let mut tail = v;
        while self.next_member[tail as usize] != NONE {
            tail = self.next_member[tail as usize];
        }
        for &c in &k[1..] {
            self.next_member[tail as usize] = c;
            let mut m = c;
            while m != NONE {
                self.rep[m as usize] = v;
                tail = m;
                m = self.next_member[m as usize];
            }
        }
    }

    /// The exact check alone. It only reads, so clusters that share no triangle can be checked in
    /// parallel, each with its own `scratch`.
    pub fn check(
        &self,
        scratch: &mut Scratch,
        positions: &[[f32; 3]],
        k: &[u32],
        new_pos: [f32; 3],
    ) -> Result<(), Reject> {
        self.collect_region(k, &mut scratch.region);
        self.check_region(scratch, positions, k, new_pos)
    }

    /// Merges `k` into `k[0]` at `new_pos` without checking; returns the triangles dropped.
    /// `region` is working memory.
    pub fn apply(
        &mut self,
        positions: &mut [[f32; 3]],
        k: &[u32],
        new_pos: [f32; 3],
        region: &mut Vec<u32>,
    ) -> usize {
        // Repeats need no sorting out: a repeated triangle has two vertices in `k`, so it dies
        // the first time and is skipped after.
        self.collect_region_with_repeats(k, region);
        let v = k[0];
        positions[v as usize] = new_pos;
        let mut dropped = 0;
        for &t in region.iter() {
            if !self.live(t) {
                continue;
            }
            let tri = &mut self.tris[t as usize];
            let mut inside = 0;
            for x in tri.iter_mut() {
                if k.contains(x) {
                    *x = v;
                    inside += 1;
                }
            }
            if inside >= 2 {
                *tri = DEAD;
                dropped += 1;
            }
        }
        self.chain_members(k);
        dropped
    }

    fn check_region(
        &self,
        sc: &mut Scratch,
        positions: &[[f32; 3]],
        k: &[u32],
        new_pos: [f32; 3],
    ) -> Result<(), Reject> {
        sc.small = false;
        match self.check_small_region(sc, positions, k, new_pos) {
            Some(verdict) => {
                sc.small = true;
                verdict
            }
            None => self.check_any_region(sc, positions, k, new_pos),
        }
    }

    /// Conditions 2 and 3 for one triangle of R with exactly one vertex `x` in K, far edge
    /// `u w`: the new triangle `v u w` keeps the old one's facing and is not flat (one that was
    /// already flat may stay flat, or open up facing like the region).
    /// `region_normal` is computed on first need (rarely: only for triangles already flat).
    fn cone_triangle_geometry(
        &self,
        region: &[u32],
        positions: &[[f32; 3]],
        [x, u, w]: [u32; 3],
        p: glam::Vec3,
        region_normal: &mut Option<glam::Vec3>,
    ) -> Result<(), Reject> {
        let [pu, pw, px] = [u, w, x].map(|i| glam::Vec3::from(positions[i as usize]));
        let mut old = (pu - px).cross(pw - px);
        let new = (pu - p).cross(pw - p);
        let longest = (pu - p)
            .length_squared()
            .max((pw - p).length_squared())
            .max((pw - pu).length_squared());
        let old_longest = (pu - px)
            .length_squared()
            .max((pw - px).length_squared())
            .max((pw - pu).length_squared());
        let was_flat = old.length() <= 1e-6 * old_longest;
        let is_flat = new.length() <= 1e-6 * longest;
        if was_flat {
            // Already flat (crossings on top of each other where the surface passes through
            // sample points): staying flat is no worse, and lets such spots be welded one
            // pair at a time; if it opens up, it must face like the region.
            if is_flat {
                return Ok(());
            }
            old = *region_normal.get_or_insert_with(|| self.region_normal(region, positions));
        }
        if old.dot(new) <= 0.0 || is_flat {
            return Err(Reject::Flip);
        }
        Ok(())
    }

    /// The facing of the whole region (sum of its triangles' area vectors).
    fn region_normal(&self, region: &[u32], positions: &[[f32; 3]]) -> glam::Vec3 {
        let mut n = glam::Vec3::ZERO;
        for &t in region {
            let [a, b, c] = self.tris[t as usize].map(|i| glam::Vec3::from(positions[i as usize]));
            n += (b - a).cross(c - a);
        }
        n
    }

    /// The exact check on bit sets, for regions of at most [`SMALL`] vertices (almost all):
    /// vertices get local ids, directed edges become one bit set per start vertex. Decides
    /// exactly as [`MergeBuffers::check_any_region`]; `None` when the region is larger.
    fn check_small_region(
        &self,
        sc: &mut Scratch,
        positions: &[[f32; 3]],
        k: &[u32],
        new_pos: [f32; 3],
    ) -> Option<Result<(), Reject>> {
        let ids = &mut sc.local;
        ids.clear();
        sc.tri_local.clear();
        let (out, incoming, bnd) = (&mut sc.out, &mut sc.incoming, &mut sc.bnd);
        let mut directed = 0usize;
        for &t in &sc.region {
            let tri = self.tris[t as usize];
            let mut l = [0usize; 3];
            for (x, &v) in l.iter_mut().zip(&tri) {
                let before = ids.filled.len();
                *x = ids.get_or_insert(v)?;
                if *x == before {
                    // A new local id: clear its rows.
                    out[*x] = 0;
                    incoming[*x] = 0;
                }
            }
            sc.tri_local.push(l.map(|x| x as u8));
            for e in 0..3 {
                let (a, b) = (l[e], l[(e + 1) % 3]);
                if out[a] & (1 << b) != 0 {
                    // Two triangles traverse one edge the same way: already broken.
                    return Some(Err(Reject::NotADisc));
                }
                out[a] |= 1 << b;
                incoming[b] |= 1 << a;
                directed += 1;
            }
        }
        let n = ids.filled.len();
        let mut kmask = 0u64;
        for &c in k {
            if let Some(l) = ids.get(c) {
                kmask |= 1 << l;
            }
        }
        sc.kmask = kmask;
        // Boundary edges (no reverse) per start vertex.
        let mut boundary = 0usize;
        for a in 0..n {
            bnd[a] = out[a] & !incoming[a];
            let c = bnd[a].count_ones() as usize;
            if c == 0 {
                continue;
            }
            // The boundary avoids K, and each vertex starts at most one boundary edge.
            if c > 1 || kmask & (1 << a) != 0 || bnd[a] & kmask != 0 {
                return Some(Err(Reject::NotADisc));
            }
            boundary += 1;
        }
        let euler = n as i64 - (directed + boundary) as i64 / 2 + sc.region.len() as i64;
        if euler != 1 || boundary < 3 {
            return Some(Err(Reject::NotADisc));
        }
        // One simple cycle: walking from any boundary edge visits all of them.
        let start = (0..n).find(|&a| bnd[a] != 0)?;
        let (mut cur, mut steps) = (start, 0usize);
        loop {
            if bnd[cur] == 0 {
                return Some(Err(Reject::NotADisc));
            }
            cur = bnd[cur].trailing_zeros() as usize;
            steps += 1;
            if cur == start || steps > boundary {
                break;
            }
        }
        if cur != start || steps != boundary {
            return Some(Err(Reject::NotADisc));
        }
        // The surviving triangles must be exactly the cone over the boundary cycle.
        let p = glam::Vec3::from(new_pos);
        let mut region_normal = None;
        // Each boundary vertex starts one boundary edge: one bit per start vertex marks it used.
        let mut used = 0u64;
        let mut cone = 0;
        for (&t, l) in sc.region.iter().zip(&sc.tri_local) {
            let tri = self.tris[t as usize];
            let l = l.map(usize::from);
            let in_k = l.map(|x| kmask & (1 << x) != 0);
            if in_k.iter().filter(|&&b| b).count() != 1 {
                continue;
            }
            let r = in_k.iter().position(|&b| b).unwrap_or(0);
            let (u, w) = (l[(r + 1) % 3], l[(r + 2) % 3]);
            if bnd[u] & (1 << w) == 0 || used & (1 << u) != 0 {
                return Some(Err(Reject::NotACone));
            }
            used |= 1 << u;
            cone += 1;
            let rotated = [tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]];
            if let Err(e) =
                self.cone_triangle_geometry(&sc.region, positions, rotated, p, &mut region_normal)
            {
                return Some(Err(e));
            }
        }
        if cone != boundary {
            return Some(Err(Reject::NotACone));
        }
        Some(Ok(()))
    }

    /// The exact check for a region of any size, on sorted edge lists.
    fn check_any_region(
        &self,
        sc: &mut Scratch,
        positions: &[[f32; 3]],
        k: &[u32],
        new_pos: [f32; 3],
    ) -> Result<(), Reject> {
        // Directed edges and vertices of R.
        sc.edges.clear();
        sc.verts.clear();
        for &t in &sc.region {
            let tri = self.tris[t as usize];
            for e in 0..3 {
                sc.edges.push((tri[e], tri[(e + 1) % 3]));
                sc.verts.push(tri[e]);
            }
        }
        sc.edges.sort_unstable();
        if sc.edges.windows(2).any(|w| w[0] == w[1]) {
            // Two triangles traverse one edge the same way: already broken, do not touch.
            return Err(Reject::NotADisc);
        }
        sc.verts.sort_unstable();
        sc.verts.dedup();
        sc.boundary.clear();
        for &(a, b) in &sc.edges {
            if sc.edges.binary_search(&(b, a)).is_err() {
                sc.boundary.push((a, b));
            }
        }
        let d = sc.edges.len() as i64;
        let b = sc.boundary.len() as i64;
        let euler = sc.verts.len() as i64 - (d + b) / 2 + sc.region.len() as i64;
        if euler != 1 || b < 3 {
            return Err(Reject::NotADisc);
        }
        // The boundary must be one simple cycle avoiding K: each vertex starts exactly one
        // boundary edge, and walking from the first edge visits all of them.
        if sc
            .boundary
            .iter()
            .any(|(a, b)| k.contains(a) || k.contains(b))
        {
            return Err(Reject::NotADisc);
        }
        // `boundary` is sorted by start vertex (it was filtered from sorted `edges`).
        if sc.boundary.windows(2).any(|w| w[0].0 == w[1].0) {
            return Err(Reject::NotADisc);
        }
        let start = sc.boundary[0];
        let mut cur = start;
        let mut steps = 1;
        loop {
            let next = match sc.boundary.binary_search_by_key(&cur.1, |e| e.0) {
                Ok(i) => sc.boundary[i],
                Err(_) => return Err(Reject::NotADisc),
            };
            if next == start {
                break;
            }
            steps += 1;
            if steps > sc.boundary.len() {
                return Err(Reject::NotADisc);
            }
            cur = next;
        }
        if steps != sc.boundary.len() {
            return Err(Reject::NotADisc);
        }
        // The surviving triangles must be exactly the cone over the boundary cycle.
        sc.used.clear();
        sc.used.resize(sc.boundary.len(), false);
        let mut cone = 0;
        let p = glam::Vec3::from(new_pos);
        // Facing of the whole region, for triangles that were flat before the merge.
        let mut region_normal = None;
        for &t in &sc.region {
            let tri = self.tris[t as usize];
            let inside = tri.iter().filter(|x| k.contains(x)).count();
            if inside != 1 {
                continue;
            }
            let r = tri.iter().position(|x| k.contains(x)).unwrap_or(0);
            let (x, u, w) = (tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]);
            let i = sc
                .boundary
                .binary_search(&(u, w))
                .map_err(|_| Reject::NotACone)?;
            if std::mem::replace(&mut sc.used[i], true) {
                return Err(Reject::NotACone);
            }
            cone += 1;
            // Geometry: the new triangle keeps the old one's facing and is not flat.
            self.cone_triangle_geometry(&sc.region, positions, [x, u, w], p, &mut region_normal)?;
        }
        if cone != sc.boundary.len() {
            return Err(Reject::NotACone);
        }
        Ok(())
    }

    /// [`rmt_mesh::Mesh::drop_unused_vertices`] with the member chains as working memory: what
    /// [`MergeBuffers::finish`] leaves of a mesh loaded and merged nothing, without building the
    /// adjacency. Like `finish`, it ends any merging in progress.
    pub fn drop_unused_vertices(&mut self, mesh: &mut rmt_mesh::Mesh) {
        mesh.drop_unused_vertices(&mut self.next_member);
    }

    /// After [`MergeBuffers::finish`]: the output vertex that original vertex `v` ended up in,
    /// or `u32::MAX` ([`rmt_mesh::UNUSED_VERTEX`]) when no output triangle uses it.
    pub fn output_id(&self, v: u32) -> u32 {
        self.next_member[self.rep[v as usize] as usize]
    }

    /// Writes the merged mesh: live triangles in their original order, vertices that live
    /// triangles use, renumbered in increasing old order. Returns the number of vertices.
    ///
    /// This ends the merging: the member chains are reused as the renumbering table (no
    /// allocation), so only [`MergeBuffers::is_alive`] and [`MergeBuffers::triangle`] stay
    /// meaningful until the next load.
    pub fn finish(&mut self, positions: &mut Vec<[f32; 3]>, indices: &mut Vec<u32>) -> usize {
        let new_id = &mut self.next_member;
        new_id.clear();
        new_id.resize(positions.len(), rmt_mesh::UNUSED_VERTEX);
        let mut live = 0;
        for tri in &self.tris {
            if *tri != DEAD {
                live += 1;
                for &v in tri {
                    new_id[v as usize] = 0;
                }
            }
        }
        let kept = rmt_mesh::compact_marked_vertices(new_id, positions, None);
        indices.clear();
        indices.reserve_exact(3 * live);
        for tri in &self.tris {
            if *tri != DEAD {
                indices.extend(tri.iter().map(|&v| new_id[v as usize]));
            }
        }
        kept
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// An octahedron: 6 vertices, 8 outward triangles.
    pub(crate) fn octahedron() -> (Vec<[f32; 3]>, Vec<u32>) {
        let p = vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let idx = vec![
            0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5,
        ];
        (p, idx)
    }

    #[test]
    fn merging_an_edge_of_a_tetrahedron_is_refused() {
        // The result would be two triangles back to back: the region is the whole closed
        // surface, not a disc.
        let mut p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let idx = vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3];
        let mut m = MergeBuffers::default();
        m.load(p.len(), &idx);
        let before = p.clone();
        assert_eq!(
            m.merge(&mut p, &[0, 1], [0.5, 0.0, 0.0], true),
            Err(Reject::NotADisc)
        );
        assert_eq!(p, before, "a refused merge changes nothing");
    }

    #[test]
    fn merging_an_edge_of_an_octahedron_passes_the_link_condition() {
        // link(0) and link(2) share exactly the edge's two opposite vertices: a valid collapse
        // to a 5-vertex sphere.
        let (mut p, idx) = octahedron();
        let mut m = MergeBuffers::default();
        m.load(p.len(), &idx);
        assert_eq!(m.merge(&mut p, &[0, 2], [0.5, 0.5, 0.0], true), Ok(2));
        let mut out_i = Vec::new();
        let v = m.finish(&mut p, &mut out_i);
        assert_eq!((v, out_i.len() / 3), (5, 6));
    }

    #[test]
    fn merging_on_a_fine_sphere_keeps_it_closed() {
        // Subdivide the octahedron once (each triangle into 4), then merge an edge.
        let (mut p, idx) = subdivided_octahedron(1);
        let mut m = MergeBuffers::default();
        m.load(p.len(), &idx);
        // Vertex 0 = (1,0,0) and the midpoint toward (0,1,0).
        let k = [0u32, 6];
        let pos = ((glam::Vec3::from(p[0]) + glam::Vec3::from(p[6])) * 0.5).to_array();
        assert_eq!(m.merge(&mut p, &k, pos, true), Ok(2));
        let mut out_p = p.clone();
        let mut out_i = Vec::new();
        let v = m.finish(&mut out_p, &mut out_i);
        assert_eq!(v, p.len() - 1);
        assert_eq!(out_i.len() / 3, idx.len() / 3 - 2);
        // Euler: V - E + F = 2 with E = 3F/2 on a closed surface.
        let f = out_i.len() / 3;
        assert_eq!(v as i64 - (3 * f / 2) as i64 + f as i64, 2);
    }

    #[test]
    fn an_unchecked_merge_goes_through_even_when_it_breaks_the_mesh() {
        let (mut p, idx) = octahedron();
        let mut m = MergeBuffers::default();
        m.load(p.len(), &idx);
        assert_eq!(m.merge(&mut p, &[0, 2], [0.5, 0.5, 0.0], false), Ok(2));
    }

    /// The octahedron subdivided `levels` times, on the unit sphere.
    fn subdivided_octahedron(levels: usize) -> (Vec<[f32; 3]>, Vec<u32>) {
        let (mut p, mut idx) = octahedron();
        for _ in 0..levels {
            let mut mid = std::collections::HashMap::new();
            let mut next = Vec::new();
            let mut midpoint = |a: u32, b: u32, p: &mut Vec<[f32; 3]>| -> u32 {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    let m = (glam::Vec3::from(p[a as usize]) + glam::Vec3::from(p[b as usize]))
                        .normalize();
                    p.push(m.to_array());
                    (p.len() - 1) as u32
                })
            };
            for t in idx.chunks_exact(3) {
                let (a, b, c) = (t[0], t[1], t[2]);
                let (ab, bc, ca) = (
                    midpoint(a, b, &mut p),
                    midpoint(b, c, &mut p),
                    midpoint(c, a, &mut p),
                );
                next.extend([a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
            }
            idx = next;
        }
        (p, idx)
    }

    #[test]
    fn merges_chain_their_members() {
        // Vertex v with its lowest-numbered neighbour, over a fine sphere: every current
        // vertex's member chain holds exactly the original vertices merged into it, and the
        // result is still a sphere.
        let (mut p, idx) = subdivided_octahedron(2);
        let mut m = MergeBuffers::default();
        m.load(p.len(), &idx);
        let mut merged = 0;
        for v in 0..p.len() as u32 {
            if m.rep(v) != v {
                continue;
            }
            let near = (0..m.triangle_count())
                .filter(|&t| m.is_alive(t) && m.triangle(t).contains(&v))
                .flat_map(|t| m.triangle(t))
                .filter(|&u| u != v)
                .min();
            let Some(u) = near else { continue };
            let centre = ((glam::Vec3::from(p[v as usize]) + glam::Vec3::from(p[u as usize]))
                * 0.5)
                .to_array();
            merged += usize::from(m.merge(&mut p, &[v, u], centre, true).is_ok());
        }
        assert!(merged > 10, "only {merged} merges went through");
        let mut owners = vec![0u32; p.len()];
        for v in 0..p.len() as u32 {
            owners[m.rep(v) as usize] += 1;
        }
        for v in 0..p.len() as u32 {
            if m.rep(v) == v {
                assert_eq!(m.member_count(v), owners[v as usize], "vertex {v}");
            }
        }
        let (mut out_p, mut out_i) = (p.clone(), Vec::new());
        let v = m.finish(&mut out_p, &mut out_i);
        let f = out_i.len() / 3;
        assert_eq!(
            v as i64 - (3 * f / 2) as i64 + f as i64,
            2,
            "still a sphere"
        );
    }
}
