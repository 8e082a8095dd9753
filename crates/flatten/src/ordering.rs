//! Nested-dissection fill-reducing ordering for the sparse Cholesky factorisations of mesh
//! systems.
//!
//! The matrices of this crate live on the graph of a triangulated disk, a planar graph. For
//! planar graphs nested dissection (George 1973; Lipton, Rose & Tarjan 1979) bounds the fill of
//! the Cholesky factor by O(n log n) and its work by O(n^1.5); minimum-degree orderings such as
//! faer's AMD have no such bound. On triangulated grids this ordering's fill is 13 % below AMD's
//! at 200k–360k vertices and above it below ~60k (`sparse::NESTED_DISSECTION_FROM`). The
//! separators come from breadth-first level structures (George & Liu's automatic nested
//! dissection): from a pseudo-peripheral node, the BFS levels of a planar mesh are arcs of
//! O(√n) nodes, and the level that splits the region in two balanced halves with the fewest
//! nodes is the separator. The halves are ordered first, recursively, the separator last;
//! regions of at most [`LEAF_NODES`] nodes are ordered by faer's AMD.
//!
//! Written here (not taken from a library) because faer 0.24 ships only AMD/COLAMD, and the Rust
//! bindings of METIS compile its C sources, which this pure-Rust crate does not take on; the
//! algorithm is ~250 lines. It uses no hashing, and the split of a region depends on its nodes
//! alone, so the halves of large regions are ordered side by side on rayon's threads
//! ([`PARALLEL_FROM`]) and the ordering, and with it every bit of every factorisation, is the
//! same on every run with any number of threads.
//!
//! The ordering works on a quotient graph: unknowns that belong to one mesh vertex (its u and v
//! coordinates) form one node, so the graph is the mesh's vertex graph, half or a quarter the
//! size of the matrix graph, and the unknowns of a node are eliminated together ([`expand`]).
//!
//! The order depends on the vertex graph alone, so a map orders it once: LSCM orders the mesh's
//! graph ([`Graph::of_triangles`], its pins included) rather than the graph of its free
//! unknowns, while it assembles its matrix, and the Newton solve it starts, whose matrix has
//! that graph, gets the same order back from [`shared_dissection`] (about 2 s of CPU each time
//! at a million faces).

/// Regions of at most this many nodes are not dissected further: their fill is bounded by a
/// dense block of this size, and splitting them would cost more than it saves.
const LEAF_NODES: usize = 256;
/// Breadth-first sweeps spent looking for a pseudo-peripheral start node (each moves to a node of
/// the last level; two or three suffice on meshes).
const PERIPHERAL_SWEEPS: usize = 4;
/// Each side of a separator must hold at least this fraction of its region's nodes.
const MIN_BALANCE: f64 = 0.3;
/// [`MIN_BALANCE`] of the root region (the whole graph), whose two halves a large factorisation
/// factors beside each other (`sparse::split`): its time is the larger half's. At 0.3 a
/// million-face toe split 301k / 699k unknowns (separator 1,554), the larger half 70 % of the
/// factorisation; at 0.45, 451k / 549k (separator 1,634) with 0.4 % less fill.
const ROOT_BALANCE: f64 = 0.45;

use std::sync::{Arc, Condvar, Mutex};

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;

/// An undirected graph in compressed adjacency form (each edge stored in both directions, no
/// self-loops, neighbours sorted).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Graph {
    ptr: Vec<usize>,
    adj: Vec<u32>,
}

impl Graph {
    /// The quotient graph of the symmetric pattern given by one triangle in compressed-column
    /// form (`col_ptr`, `row_idx`, either triangle): unknown `i` belongs to node `node_of[i]`
    /// (`< n_nodes`), and two nodes are adjacent when any of their unknowns are coupled.
    pub fn quotient(col_ptr: &[usize], row_idx: &[usize], node_of: &[u32], n_nodes: usize) -> Self {
        let n = col_ptr.len().saturating_sub(1);
        Self::from_edges(n_nodes, || {
            (0..n).flat_map(move |c| {
                row_idx[col_ptr[c]..col_ptr[c + 1]]
                    .iter()
                    .map(move |&r| (node_of[r], node_of[c]))
            })
        })
    }

    /// The vertex graph of a triangle mesh with `n_vertices` vertices: two vertices are
    /// adjacent when they share a triangle. The same graph as the quotient of any map's
    /// matrix on the mesh whose unknowns are all free (the Newton systems'), which lets LSCM,
    /// whose pinned unknowns are not in its matrix, share its ordering ([`shared_dissection`]).
    pub fn of_triangles(n_vertices: usize, triangles: &[[u32; 3]]) -> Self {
        Self::from_edges(n_vertices, || {
            triangles
                .iter()
                .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        })
    }

    /// The graph on `n_nodes` nodes of the pairs `edges` yields (either direction, duplicates
    /// and self-loops allowed and dropped); `edges` is called twice.
    fn from_edges<I: Iterator<Item = (u32, u32)>>(n_nodes: usize, edges: impl Fn() -> I) -> Self {
        let edges = || edges().filter(|(a, b)| a != b);
        let mut ptr = vec![0usize; n_nodes + 1];
        for (a, b) in edges() {
            ptr[a as usize + 1] += 1;
            ptr[b as usize + 1] += 1;
        }
        for i in 0..n_nodes {
            ptr[i + 1] += ptr[i];
        }
        let mut fill = ptr.clone();
        let mut adj = vec![0u32; ptr[n_nodes]];
        for (a, b) in edges() {
            adj[fill[a as usize]] = b;
            fill[a as usize] += 1;
            adj[fill[b as usize]] = a;
            fill[b as usize] += 1;
        }
        drop(fill);
        // Sort and deduplicate each list in place, compacting as we go.
        let mut out = 0;
        let mut start = 0;
        for v in 0..n_nodes {
            let end = ptr[v + 1];
            adj[start..end].sort_unstable();
            ptr[v] = out;
            let mut last = None;
            for k in start..end {
                let w = adj[k];
                if last != Some(w) {
                    adj[out] = w;
                    out += 1;
                    last = Some(w);
                }
            }
            start = end;
        }
        ptr[n_nodes] = out;
        adj.truncate(out);
        adj.shrink_to_fit();
        Self { ptr, adj }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.ptr.len() - 1
    }

    /// The neighbours of `v`, sorted.
    pub(crate) fn neighbours(&self, v: u32) -> &[u32] {
        &self.adj[self.ptr[v as usize]..self.ptr[v as usize + 1]]
    }

    /// Where the neighbours of `v` start among all nodes' neighbours (node by node, as
    /// [`Graph::neighbours`] lists them): a value per entry can be kept beside the graph.
    pub(crate) fn first_neighbour(&self, v: u32) -> usize {
        self.ptr[v as usize]
    }

    /// The number of entries of all nodes' neighbour lists (twice the number of edges).
    pub(crate) fn n_neighbours(&self) -> usize {
        self.adj.len()
    }
}

/// A region still to be ordered: its nodes and the first position they take.
struct Region {
    id: u32,
    nodes: Vec<u32>,
    first: usize,
}

/// Scratch state of the dissection: which region each node is in and its BFS level.
struct Dissection<'g> {
    g: &'g Graph,
    region: Vec<u32>,
    level: Vec<u32>,
    queue: Vec<u32>,
    /// Index of each node within the leaf being ordered (scratch of [`Self::order_leaf`]).
    local: Vec<u32>,
    next_id: u32,
    /// The position in the whole order of the first entry of the slice this dissection writes.
    base: usize,
    /// The first positions of the leaves and separators placed ([`Dissected::groups`]).
    groups: Vec<u32>,
}

const UNSEEN: u32 = u32::MAX;

impl<'g> Dissection<'g> {
    /// Scratch for ordering region `r` of `g` into a slice of the order that starts at its
    /// first position: its nodes marked as its, every other node as outside it.
    fn for_region(g: &'g Graph, r: &Region) -> Self {
        let n = g.len();
        let mut region = vec![UNSEEN; n];
        for &v in &r.nodes {
            region[v as usize] = r.id;
        }
        Self {
            g,
            region,
            level: vec![UNSEEN; n],
            queue: Vec::new(),
            local: vec![0; n],
            next_id: r.id,
            base: r.first,
            groups: Vec::new(),
        }
    }

    /// Breadth-first search from `root` inside region `id`: fills `queue` with the nodes reached
    /// in BFS order and `level` with their distances; returns the number of levels.
    fn bfs(&mut self, id: u32, root: u32) -> u32 {
        self.queue.clear();
        self.queue.push(root);
        self.level[root as usize] = 0;
        let mut head = 0;
        while head < self.queue.len() {
            let v = self.queue[head];
            head += 1;
            let lv = self.level[v as usize];
            for &w in self.g.neighbours(v) {
                if self.region[w as usize] == id && self.level[w as usize] == UNSEEN {
                    self.level[w as usize] = lv + 1;
                    self.queue.push(w);
                }
            }
        }
        self.queue.last().map_or(0, |&v| self.level[v as usize] + 1)
    }

    fn clear_levels(&mut self) {
        for &v in &self.queue {
            self.level[v as usize] = UNSEEN;
        }
    }

    /// A BFS from a pseudo-peripheral node of the component of `nodes[0]` (the level structure
    /// stays in `queue`/`level`); returns the number of levels.
    fn peripheral_bfs(&mut self, id: u32, start: u32) -> u32 {
        let mut depth = self.bfs(id, start);
        for _ in 0..PERIPHERAL_SWEEPS {
            let last = depth - 1;
            let g = self.g;
            let Some(&cand) = self
                .queue
                .iter()
                .rev()
                .take_while(|&&v| self.level[v as usize] == last)
                .min_by_key(|&&v| (g.neighbours(v).len(), v))
            else {
                break;
            };
            self.clear_levels();
            let d = self.bfs(id, cand);
            // The level structure now in `queue`/`level` is the one from `cand`: report its
            // depth even when it is not deeper, and stop.
            let deeper = d > depth;
            depth = d;
            if !deeper {
                break;
            }
        }
        depth
    }

    fn new_id(&mut self) -> u32 {
        self.next_id += 1;
        self.next_id
    }

    /// Splits `r` into the regions to order before it; writes the nodes it places (a leaf, or a
    /// separator) into `order`.
    fn split(&mut self, r: Region, order: &mut [u32]) -> Vec<Region> {
        let n = r.nodes.len();
        if n <= LEAF_NODES {
            self.order_leaf(&r, order);
            return Vec::new();
        }
        let depth = self.peripheral_bfs(r.id, r.nodes[0]);
        if self.queue.len() < n {
            // Disconnected: the component found and the rest are independent regions.
            let comp = std::mem::take(&mut self.queue);
            let (a, b) = (self.new_id(), self.new_id());
            for &v in &comp {
                self.region[v as usize] = a;
                self.level[v as usize] = UNSEEN;
            }
            let rest: Vec<u32> = r
                .nodes
                .iter()
                .copied()
                .filter(|&v| self.region[v as usize] == r.id)
                .collect();
            for &v in &rest {
                self.region[v as usize] = b;
            }
            let first_rest = r.first + comp.len();
            return vec![
                Region {
                    id: a,
                    nodes: comp,
                    first: r.first,
                },
                Region {
                    id: b,
                    nodes: rest,
                    first: first_rest,
                },
            ];
        }
        let Some(m) = self.separator_level(depth as usize) else {
            // No level splits the region in balanced parts (a near-clique): order it as it is.
            self.clear_levels();
            self.order_leaf(&r, order);
            return Vec::new();
        };
        let m = m as u32;
        let (below, above) = (self.new_id(), self.new_id());
        let (mut a, mut b, mut sep) = (Vec::new(), Vec::new(), Vec::new());
        for &v in &self.queue {
            let l = self.level[v as usize];
            if l < m || (l == m && !self.touches_level(v, r.id, m + 1)) {
                a.push(v);
            } else if l == m {
                sep.push(v);
            } else {
                b.push(v);
            }
        }
        self.clear_levels();
        for &v in &a {
            self.region[v as usize] = below;
        }
        for &v in &b {
            self.region[v as usize] = above;
        }
        let sep_first = r.first + a.len() + b.len();
        let at = sep_first - self.base;
        order[at..at + sep.len()].copy_from_slice(&sep);
        self.groups.push(sep_first as u32);
        for &v in &sep {
            self.region[v as usize] = UNSEEN;
        }
        let first_b = r.first + a.len();
        vec![
            Region {
                id: below,
                nodes: a,
                first: r.first,
            },
            Region {
                id: above,
                nodes: b,
                first: first_b,
            },
        ]
    }

    /// Orders a region that is not dissected further by minimum degree (faer's AMD on its
    /// subgraph). A plain breadth-first order of the leaves gave about 10 % more fill and, worse,
    /// no supernodes: every leaf column became its own one-column supernode and the numeric
    /// factorisation ran 4× slower than with AMD alone.
    fn order_leaf(&mut self, r: &Region, order: &mut [u32]) {
        let n = r.nodes.len();
        self.groups.push(r.first as u32);
        for (k, &v) in r.nodes.iter().enumerate() {
            self.local[v as usize] = k as u32;
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0usize);
        for &v in &r.nodes {
            row_idx.extend(
                self.g
                    .neighbours(v)
                    .iter()
                    .filter(|&&w| self.region[w as usize] == r.id)
                    .map(|&w| self.local[w as usize] as usize),
            );
            let start = col_ptr[col_ptr.len() - 1];
            row_idx[start..].sort_unstable();
            col_ptr.push(row_idx.len());
        }
        let (mut perm, mut perm_inv) = (vec![0usize; n], vec![0usize; n]);
        let nnz = row_idx.len();
        let graph = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let mut mem = MemBuffer::new(amd::order_scratch::<usize>(n, nnz));
        let amd_ok = amd::order(
            &mut perm,
            &mut perm_inv,
            graph,
            amd::Control::default(),
            MemStack::new(&mut mem),
        )
        .is_ok();
        for k in 0..n {
            let local = if amd_ok { perm[k] } else { k };
            order[r.first - self.base + k] = r.nodes[local];
        }
    }

    /// True when `v` has a neighbour in region `id` at BFS level `l`.
    fn touches_level(&self, v: u32, id: u32, l: u32) -> bool {
        self.g
            .neighbours(v)
            .iter()
            .any(|&w| self.region[w as usize] == id && self.level[w as usize] == l)
    }

    /// The level whose nodes touching the next level form the smallest separator with at least
    /// [`MIN_BALANCE`] of the region on each side ([`ROOT_BALANCE`] for the whole graph), `None`
    /// if no level qualifies.
    fn separator_level(&self, depth: usize) -> Option<usize> {
        if depth < 3 {
            return None;
        }
        let id = self.region[self.queue[0] as usize];
        let mut count = vec![0usize; depth];
        let mut sep = vec![0usize; depth];
        for &v in &self.queue {
            let l = self.level[v as usize] as usize;
            count[l] += 1;
            if l + 1 < depth && self.touches_level(v, id, l as u32 + 1) {
                sep[l] += 1;
            }
        }
        let n = self.queue.len();
        let balance = if n == self.g.len() {
            ROOT_BALANCE
        } else {
            MIN_BALANCE
        };
        let min_side = (balance * n as f64).ceil() as usize;
        let mut before = 0;
        let mut best: Option<(usize, usize)> = None;
        for m in 0..depth {
            let below = before + count[m] - sep[m];
            let above = n - before - count[m];
            before += count[m];
            if m == 0 || m + 1 >= depth || below < min_side || above < min_side {
                continue;
            }
            if best.is_none_or(|(s, _)| sep[m] < s) {
                best = Some((sep[m], m));
            }
        }
        best.map(|(_, m)| m)
    }
}

/// A nested-dissection order of a graph's nodes, with the blocks it is made of.
#[derive(Debug, PartialEq, Eq)]
pub struct Dissected {
    /// `order[k]` is the node eliminated k-th.
    pub order: Vec<u32>,
    /// The first position of every leaf and separator in `order`, increasing (from 0): the
    /// nodes of one block are eliminated together.
    pub groups: Vec<u32>,
}

/// The nested-dissection elimination order of `g`: `order[k]` is the node eliminated k-th.
#[cfg(test)]
pub fn nested_dissection(g: &Graph) -> Vec<u32> {
    dissection(g).order
}

/// The nested-dissection order of `g` with its blocks.
pub fn dissection(g: &Graph) -> Dissected {
    let n = g.len();
    let mut order = vec![0u32; n];
    let root = Region {
        id: 0,
        nodes: (0..n as u32).collect(),
        first: 0,
    };
    let mut groups = dissect(g, root, &mut order);
    groups.sort_unstable();
    if groups.first() != Some(&0) {
        groups.insert(0, 0);
    }
    Dissected { order, groups }
}

/// Regions of at least this many nodes, in the top [`PARALLEL_LEVELS`] levels of the
/// dissection, have their two halves ordered side by side (rayon): the first half on the
/// region's scratch, the second on scratch of its own (12 bytes a node of the graph). The split
/// of a region depends on its nodes alone, so the order is the same bits as one thread's.
const PARALLEL_FROM: usize = 60_000;
/// Levels of the dissection whose halves are ordered side by side: four parts at the most,
/// enough for two cores, and four sets of scratch.
const PARALLEL_LEVELS: usize = 2;

/// Orders region `r` into `order`, the slice of the whole order from `r.first` on; returns the
/// first positions of the blocks placed (in no particular order).
fn dissect(g: &Graph, r: Region, order: &mut [u32]) -> Vec<u32> {
    let d = Dissection::for_region(g, &r);
    dissect_on(d, r, order, 0)
}

/// [`dissect`] on the scratch `d` (its region marks hold `r`'s nodes as `r`'s), `level` levels
/// below the top.
fn dissect_on(mut d: Dissection<'_>, r: Region, order: &mut [u32], level: usize) -> Vec<u32> {
    if r.nodes.len() < PARALLEL_FROM || level >= PARALLEL_LEVELS {
        let mut stack = vec![r];
        while let Some(r) = stack.pop() {
            stack.extend(d.split(r, order));
        }
        return d.groups;
    }
    let first = r.first;
    let mut halves = d.split(r, order);
    let mut groups = std::mem::take(&mut d.groups);
    let (Some(b), Some(a)) = (halves.pop(), halves.pop()) else {
        return groups;
    };
    // The first half starts where the region did, so the region's scratch writes it.
    let (lo, hi) = order.split_at_mut(b.first - first);
    let lo = &mut lo[..a.nodes.len()];
    let hi = &mut hi[..b.nodes.len()];
    let g = d.g;
    let (ga, gb) = rayon::join(
        move || dissect_on(d, a, lo, level + 1),
        || dissect_on(Dissection::for_region(g, &b), b, hi, level + 1),
    );
    groups.extend(ga);
    groups.extend(gb);
    groups
}

/// The last nested-dissection order made (or being made), with its graph, until an equal graph
/// asks for it: a map's start (LSCM) and the Newton solve after it order the same vertex graph,
/// the Newton solve's analysis on a thread of its own while the start map is made
/// (`nonlinear::solve`). Handed out once and then dropped, so that the graph (16 MB at a
/// million faces) is not held through the Newton solve's factorisations, the memory peak of a
/// large map.
static LAST: Mutex<Memo> = Mutex::new(Memo::Empty);
/// Woken when an order being made is made (or its making has failed).
static MADE: Condvar = Condvar::new();

/// What [`LAST`] holds.
enum Memo {
    Empty,
    /// The order of this graph is being made by a thread: a call with an equal graph waits for it.
    Making(Arc<Graph>),
    /// The order of this graph, made and not yet handed out.
    Made(Arc<Graph>, Arc<Dissected>),
}

/// [`nested_dissection`] of `g`, made once for two equal graphs in a row: the order of the last
/// graph ordered is kept, and handed to the next call if its graph is equal (compared whole,
/// so the order is always the one `g` would get: the same bits as computing it again). A call
/// made while an equal graph is being ordered waits for that order instead of making its own
/// (except on one of rayon's threads); the lock is not held while an order is computed.
pub fn shared_dissection(g: Graph) -> Arc<Dissected> {
    shared_dissection_of(Arc::new(g))
}

/// [`shared_dissection`] of a graph its caller holds too (LSCM keeps its values beside it).
pub fn shared_dissection_of(g: Arc<Graph>) -> Arc<Dissected> {
    let Ok(mut memo) = LAST.lock() else {
        return Arc::new(dissection(&g));
    };
    loop {
        match &*memo {
            Memo::Made(h, _) if **h == *g => {
                if let Memo::Made(_, order) = std::mem::replace(&mut *memo, Memo::Empty) {
                    return order;
                }
            }
            // One of rayon's threads never waits: the order it would wait for may be held up
            // behind it (its maker's halves, `dissect_on`, waiting in a join that this thread
            // would otherwise take part in). It orders the graph itself, as before there was a
            // memo.
            Memo::Making(h) if **h == *g && rayon::current_thread_index().is_some() => {
                drop(memo);
                return Arc::new(dissection(&g));
            }
            Memo::Making(h) if **h == *g => match MADE.wait(memo) {
                Ok(m) => memo = m,
                Err(_) => return Arc::new(dissection(&g)),
            },
            _ => break,
        }
    }
    *memo = Memo::Making(Arc::clone(&g));
    drop(memo);
    let making = Making(&g);
    let order = Arc::new(dissection(&g));
    making.made(Some(&order));
    order
}

/// The order of a graph being made by this thread ([`shared_dissection`]): when it is dropped
/// unmade (a panic), the memo is cleared and the waiting calls are woken to make their own.
struct Making<'a>(&'a Arc<Graph>);

impl Making<'_> {
    /// Keeps `order` (if any) as the order of this graph, unless the memo has moved on to
    /// another graph, and wakes the waiting calls.
    fn made(self, order: Option<&Arc<Dissected>>) {
        if let Ok(mut memo) = LAST.lock()
            && matches!(&*memo, Memo::Making(h) if Arc::ptr_eq(h, self.0))
        {
            *memo = match order {
                Some(o) => Memo::Made(Arc::clone(self.0), Arc::clone(o)),
                None => Memo::Empty,
            };
        }
        MADE.notify_all();
        std::mem::forget(self);
    }
}

impl Drop for Making<'_> {
    fn drop(&mut self) {
        Making(self.0).made(None);
    }
}

/// The elimination order of the unknowns: nodes in `node_order`, the unknowns of one node
/// together in increasing index. Every unknown appears once (`node_of[i] < node_order.len()`).
pub fn expand(node_order: &[u32], node_of: &[u32]) -> Vec<usize> {
    let members = Members::new(node_of, node_order.len());
    node_order
        .iter()
        .flat_map(|&v| members.of(v).iter().copied())
        .collect()
}

/// The unknowns of each node, in increasing index.
struct Members {
    ptr: Vec<usize>,
    members: Vec<usize>,
}

impl Members {
    fn new(node_of: &[u32], n_nodes: usize) -> Self {
        let mut ptr = vec![0usize; n_nodes + 1];
        for &v in node_of {
            ptr[v as usize + 1] += 1;
        }
        for i in 0..n_nodes {
            ptr[i + 1] += ptr[i];
        }
        let mut members = vec![0usize; node_of.len()];
        let mut fill = ptr.clone();
        for (i, &v) in node_of.iter().enumerate() {
            members[fill[v as usize]] = i;
            fill[v as usize] += 1;
        }
        Self { ptr, members }
    }

    fn of(&self, v: u32) -> &[usize] {
        &self.members[self.ptr[v as usize]..self.ptr[v as usize + 1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 5-point grid graph on `w × h` nodes, upper triangle in compressed-column form.
    fn grid(w: usize, h: usize) -> (Vec<usize>, Vec<usize>) {
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for c in 0..w * h {
            let (x, y) = (c % w, c / w);
            if y > 0 {
                row_idx.push(c - w);
            }
            if x > 0 {
                row_idx.push(c - 1);
            }
            row_idx.push(c);
            col_ptr.push(row_idx.len());
        }
        (col_ptr, row_idx)
    }

    #[test]
    fn calls_made_while_an_equal_graph_is_ordered_get_its_order() {
        // Four threads at once on one graph (a unique size, so no other test's graph is
        // equal): whichever makes the order, every one gets the graph's own order, and none
        // hangs waiting.
        let (w, h) = (171, 97);
        let (col_ptr, row_idx) = grid(w, h);
        let node_of: Vec<u32> = (0..(w * h) as u32).collect();
        let g = Graph::quotient(&col_ptr, &row_idx, &node_of, w * h);
        let want = dissection(&g);
        let got: Vec<Arc<Dissected>> = std::thread::scope(|s| {
            let calls: Vec<_> = (0..4)
                .map(|_| s.spawn(|| shared_dissection(g.clone())))
                .collect();
            calls.into_iter().map(|c| c.join().unwrap()).collect()
        });
        for order in got {
            assert_eq!(*order, want);
        }
        // And on rayon's threads, which order the graph themselves while it is being ordered.
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap();
        let got: Vec<Arc<Dissected>> = pool.install(|| {
            use rayon::prelude::*;
            (0..8)
                .into_par_iter()
                .map(|_| shared_dissection(g.clone()))
                .collect()
        });
        for order in got {
            assert_eq!(*order, want);
        }
    }

    #[test]
    fn quotient_merges_unknowns_and_drops_self_loops() {
        // Two unknowns per node on a path of three nodes: 0-1-2.
        let node_of = [0, 0, 1, 1, 2, 2];
        // Upper triangle: (0,1) inside node 0, (1,2) and (0,3) between nodes 0 and 1, (3,4)
        // between 1 and 2, plus the diagonal.
        let col_ptr = vec![0, 1, 3, 5, 7, 9, 10];
        let row_idx = vec![0, 0, 1, 1, 2, 0, 3, 3, 4, 5];
        let g = Graph::quotient(&col_ptr, &row_idx, &node_of, 3);
        assert_eq!(g.neighbours(0), &[1]);
        assert_eq!(g.neighbours(1), &[0, 2]);
        assert_eq!(g.neighbours(2), &[1]);
    }

    #[test]
    fn dissection_is_a_permutation_with_a_separator_last() {
        let (w, h) = (40, 30);
        let (col_ptr, row_idx) = grid(w, h);
        let node_of: Vec<u32> = (0..(w * h) as u32).collect();
        let g = Graph::quotient(&col_ptr, &row_idx, &node_of, w * h);
        let order = nested_dissection(&g);
        let mut seen = vec![false; w * h];
        for &v in &order {
            assert!(!seen[v as usize], "node {v} twice");
            seen[v as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
        // The last nodes form the top separator: removing them disconnects the grid into two
        // parts, each at least MIN_BALANCE of it. Find the separator as the nodes placed after
        // the last node that is adjacent to a node of the other half: here, check the cut
        // directly on the first half of the order versus the rest.
        let pos: Vec<usize> = {
            let mut p = vec![0; w * h];
            for (k, &v) in order.iter().enumerate() {
                p[v as usize] = k;
            }
            p
        };
        // Nodes of part A (placed first) never touch part B except through separator nodes,
        // which come after both: so every edge between two nodes placed before the separator
        // joins nodes on the same side. A separator of a 40 × 30 grid found by BFS levels is at
        // most a diagonal, ≤ 31 + 30 nodes.
        let n = w * h;
        let sep_len = (1..=61)
            .find(|&s| {
                let cut = n - s;
                // Split the first `cut` nodes into connected groups; they must be ≥ 2 groups.
                let mut comp = vec![usize::MAX; n];
                let mut groups = 0;
                for start in 0..n {
                    if pos[start] >= cut || comp[start] != usize::MAX {
                        continue;
                    }
                    groups += 1;
                    let mut st = vec![start];
                    comp[start] = groups;
                    while let Some(v) = st.pop() {
                        for &u in g.neighbours(v as u32) {
                            let u = u as usize;
                            if pos[u] < cut && comp[u] == usize::MAX {
                                comp[u] = groups;
                                st.push(u);
                            }
                        }
                    }
                }
                groups >= 2
            })
            .expect("the last ≤ 61 nodes separate the grid");
        assert!(sep_len <= 61, "separator of {sep_len} nodes");
    }

    #[test]
    fn the_triangle_graph_is_the_quotient_of_the_uv_pattern_and_orders_alike() {
        // A strip of 2 × 3 quads, split into triangles, plus an unused vertex 12.
        let (w, h) = (4u32, 3u32);
        let mut tris = Vec::new();
        for y in 0..h - 1 {
            for x in 0..w - 1 {
                let v = y * w + x;
                tris.push([v, v + 1, v + w + 1]);
                tris.push([v, v + w + 1, v + w]);
            }
        }
        let n = (w * h + 1) as usize;
        let g = Graph::of_triangles(n, &tris);
        // The upper triangle of the 2 × 2-block (u, v) pattern of the same triangles.
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); 2 * n];
        for t in &tris {
            for &a in t {
                for &b in t {
                    for (i, j) in [(2 * a, 2 * b), (2 * a, 2 * b + 1), (2 * a + 1, 2 * b + 1)] {
                        let (r, c) = (i.min(j) as usize, i.max(j) as usize);
                        cols[c].push(r);
                    }
                }
            }
        }
        for (c, rows) in cols.iter_mut().enumerate() {
            rows.push(c);
            rows.sort_unstable();
            rows.dedup();
        }
        let col_ptr: Vec<usize> = std::iter::once(0)
            .chain(cols.iter().scan(0, |acc, r| {
                *acc += r.len();
                Some(*acc)
            }))
            .collect();
        let row_idx: Vec<usize> = cols.concat();
        let node_of: Vec<u32> = (0..2 * n as u32).map(|i| i / 2).collect();
        assert_eq!(g, Graph::quotient(&col_ptr, &row_idx, &node_of, n));
        assert_eq!(g.neighbours(0), &[1, 4, 5]);
        assert!(g.neighbours(12).is_empty());
        // Shared or made again, the order is the same.
        assert_eq!(*shared_dissection(g.clone()), dissection(&g));
        assert_eq!(*shared_dissection(g.clone()), dissection(&g));
    }

    #[test]
    fn the_halves_ordered_side_by_side_give_the_sequential_order_with_any_threads() {
        // Large enough for the top region's halves to be ordered side by side.
        let (w, h) = (330, 240);
        let (col_ptr, row_idx) = grid(w, h);
        let n = w * h;
        assert!(n >= PARALLEL_FROM);
        let node_of: Vec<u32> = (0..n as u32).collect();
        let g = Graph::quotient(&col_ptr, &row_idx, &node_of, n);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| dissection(&g))
        };
        let (one, two) = (run(1), run(2));
        assert_eq!(
            one, two,
            "the same order and blocks with one thread and two"
        );
        // The regions one after another on one scratch, as the order was made before its
        // halves were shared out.
        let root = Region {
            id: 0,
            nodes: (0..n as u32).collect(),
            first: 0,
        };
        let mut order = vec![0u32; n];
        let mut d = Dissection::for_region(&g, &root);
        let mut stack = vec![root];
        while let Some(r) = stack.pop() {
            stack.extend(d.split(r, &mut order));
        }
        assert_eq!(two.order, order, "the sequential order");
        let mut groups = d.groups;
        groups.sort_unstable();
        assert_eq!(two.groups, groups, "the sequential blocks");
        // The blocks tile the order from 0; the last is the top separator: without it the
        // grid falls apart.
        assert_eq!(two.groups[0], 0);
        assert!(two.groups.windows(2).all(|p| p[0] < p[1]));
        let top = *two.groups.last().unwrap() as usize;
        assert!(n - top <= w.max(h) + 1, "a separator of {} nodes", n - top);
        let mut cut = vec![false; n];
        two.order[top..]
            .iter()
            .for_each(|&v| cut[v as usize] = true);
        let start = (0..n).find(|&v| !cut[v]).unwrap();
        let mut seen = cut.clone();
        let mut stack = vec![start as u32];
        seen[start] = true;
        let mut reached = 1;
        while let Some(v) = stack.pop() {
            for &u in g.neighbours(v) {
                if !seen[u as usize] {
                    seen[u as usize] = true;
                    reached += 1;
                    stack.push(u);
                }
            }
        }
        assert!(reached < top, "the top separator splits the grid");
    }

    #[test]
    fn expand_keeps_the_unknowns_of_a_node_together() {
        let node_of = [1, 0, 1, 2, 0];
        assert_eq!(expand(&[2, 0, 1], &node_of), vec![3, 1, 4, 0, 2]);
    }

    #[test]
    fn disconnected_graphs_are_ordered_whole() {
        // Two grids side by side with no edge between them.
        let (cp, ri) = grid(20, 20);
        let mut col_ptr = cp.clone();
        let mut row_idx = ri.clone();
        let off = 400;
        for c in 0..400 {
            for &r in &ri[cp[c]..cp[c + 1]] {
                row_idx.push(r + off);
            }
            col_ptr.push(row_idx.len());
        }
        let node_of: Vec<u32> = (0..800).collect();
        let g = Graph::quotient(&col_ptr, &row_idx, &node_of, 800);
        let mut order = nested_dissection(&g);
        order.sort_unstable();
        assert_eq!(order, (0..800).collect::<Vec<u32>>());
    }
}
