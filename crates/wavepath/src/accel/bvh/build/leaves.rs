//! Leaf storage, written after the collapse: each leaf of the wide tree gets its block or its
//! packed record in the store, written in parallel.
use crate::accel::bvh::tree::{
    EMPTY, LANES, LEAF_BIT, LeafStore, Line, MAX_PRIMS, Node8, PACKED_HEAD, SPARE_LINES, Tri4, WIDTH, leaf_range,
    leaf_ref,
};
use crate::scene::Scene;
use glam::Vec3;

/// Stores every leaf of `nodes`, packed or as corners, rewriting each leaf reference's
/// `first` to the leaf's place in the store. `ids` are the primitive ids in the builder's
/// leaf order. A leaf holds at most [`LANES`] primitives.
///
/// The store is collected in parallel, each unit (a block, or a line of a packed record)
/// written once by the thread that makes it: allocated first and filled after, it was
/// zeroed on one thread (an aligned allocation is zeroed by a pass of its own), and that pass
/// took most of the time, its page faults included (6.4M triangles: 110 of 180 ms).
pub fn store_leaves(nodes: &mut [Node8], ids: &[u32], scene: &Scene, packed: bool) -> LeafStore {
    use rayon::prelude::*;
    let tri_count = scene.mesh.triangle_count() as u32;
    let lane_ids = |first: u32, count: u32| {
        let mut out = [u32::MAX; LANES];
        out[..count as usize].copy_from_slice(&ids[first as usize..(first + count) as usize]);
        out
    };
    let record = |first: u32, count: u32| {
        let ids = lane_ids(first, count);
        let corners =
            std::array::from_fn(
                |lane| if ids[lane] < tri_count { scene.mesh.triangles[ids[lane] as usize] } else { [0; 3] },
            );
        Packed::of(&ids, &corners, tri_count)
    };
    // The units of each leaf, group by group (a byte a leaf, not a table of places: at 25.6M
    // triangles that took 110 MB at the peak).
    let sizes: Vec<Vec<u8>> = nodes
        .par_chunks(GROUP)
        .map(|g| {
            leaf_ranges(g).map(|(first, count)| if packed { record(first, count).lines() as u8 } else { 1 }).collect()
        })
        .collect();
    let total_leaves: usize = sizes.iter().map(Vec::len).sum();
    let starts = group_starts(&sizes);
    let total_units: usize = sizes.iter().flatten().map(|&n| n as usize).sum();
    assert!(
        total_leaves < MAX_PRIMS && total_units < MAX_PRIMS,
        "a BVH holds at most {MAX_PRIMS} leaves and leaf lines"
    );
    let walk = || Walk::new(nodes, &sizes, &starts);
    let store = if packed {
        // Each record is made twice, to count its lines and to write them: keeping them
        // between the passes would hold as much memory again as the store itself.
        let lines: Vec<Line> = (0..total_units + SPARE_LINES)
            .into_par_iter()
            .with_min_len(SEEK_EVERY)
            .map_init(
                || (walk(), usize::MAX, [0u32; 64]),
                |(w, made, words), u| {
                    if u >= total_units {
                        return Line::default();
                    }
                    let (first, count, off) = w.unit(u);
                    // The record of the leaf this line belongs to, made at its first line.
                    let leaf = u - off;
                    if *made != leaf {
                        *words = [0; 64];
                        record(first, count).write(words, &scene.mesh.positions);
                        *made = leaf;
                    }
                    Line(words[16 * off..16 * off + 16].try_into().expect("a line is 16 words"))
                },
            )
            .collect();
        LeafStore::Packed { lines, leaves: total_leaves }
    } else {
        let blocks: Vec<Tri4> = (0..total_units)
            .into_par_iter()
            .with_min_len(SEEK_EVERY)
            .map_init(walk, |w, u| {
                let (first, count, _) = w.unit(u);
                let mut block = Tri4 { ids: lane_ids(first, count), ..Tri4::default() };
                for lane in 0..count as usize {
                    let id = block.ids[lane];
                    if id < tri_count {
                        block.tri_lanes |= 1 << lane;
                        for (corner, v) in scene.mesh.corners(id as usize).iter().enumerate() {
                            for axis in 0..3 {
                                block.c[corner][axis][lane] = v[axis];
                            }
                        }
                    } else {
                        block.other_lanes |= 1 << lane;
                    }
                }
                block
            })
            .collect();
        LeafStore::Corners(blocks)
    };
    nodes.par_chunks_mut(GROUP).zip(&starts).zip(&sizes).for_each(|((g, &start), sizes)| {
        let (mut at, mut k) = (start, 0);
        for_each_leaf(g, |_, _| {
            let place = at;
            at += sizes[k] as usize;
            k += 1;
            place as u32
        });
    });
    store
}

/// Units a parallel writer makes at least (each run starts with a seek through one group).
const SEEK_EVERY: usize = 4096;

/// A position among the leaf children of `nodes` in store order (node, then slot), one
/// unit of the store (a block, or a line of a packed record) at a time: a parallel writer
/// seeks to the first unit of its run and then steps.
struct Walk<'a> {
    nodes: &'a [Node8],
    /// Units of each leaf, per group of [`GROUP`] nodes.
    sizes: &'a [Vec<u8>],
    /// First unit of each group.
    starts: &'a [usize],
    /// The unit the walk is at (`usize::MAX` before the first seek).
    next: usize,
    node: usize,
    slot: usize,
    /// The leaf's index within its group.
    leaf: usize,
    /// The unit within the leaf.
    off: usize,
}

/// The first unit of each group, from its leaves' units (`sizes`).
fn group_starts(sizes: &[Vec<u8>]) -> Vec<usize> {
    sizes
        .iter()
        .scan(0, |at, g| {
            let start = *at;
            *at += g.iter().map(|&n| n as usize).sum::<usize>();
            Some(start)
        })
        .collect()
}

impl<'a> Walk<'a> {
    /// A walk before its first seek.
    fn new(nodes: &'a [Node8], sizes: &'a [Vec<u8>], starts: &'a [usize]) -> Self {
        Walk { nodes, sizes, starts, next: usize::MAX, node: 0, slot: 0, leaf: 0, off: 0 }
    }

    /// The builder's (first, count) of the leaf holding unit `u`, and `u`'s place in it.
    fn unit(&mut self, u: usize) -> (u32, u32, usize) {
        if u != self.next {
            self.seek(u);
        }
        let (first, count) = range_of(self.nodes[self.node].child[self.slot]);
        let off = self.off;
        self.next = u + 1;
        self.off += 1;
        if self.off == self.size() {
            self.step();
        }
        (first, count, off)
    }

    fn size(&self) -> usize {
        self.sizes[self.node / GROUP][self.leaf] as usize
    }

    fn seek(&mut self, u: usize) {
        // The last group starting at or before `u` (groups without leaves start where the
        // next one does).
        let g = self.starts.partition_point(|&s| s <= u) - 1;
        (self.node, self.slot, self.leaf, self.off) = (g * GROUP, 0, 0, 0);
        if !is_leaf(self.nodes[self.node].child[0]) {
            self.step();
            self.leaf = 0;
        }
        let mut at = self.starts[g];
        while at + self.size() <= u {
            at += self.size();
            self.step();
        }
        self.off = u - at;
    }

    /// On to the next leaf child (past the last one: a node beyond the array).
    fn step(&mut self) {
        let group = self.node / GROUP;
        loop {
            self.slot += 1;
            if self.slot == WIDTH {
                (self.node, self.slot) = (self.node + 1, 0);
            }
            if self.node == self.nodes.len() || is_leaf(self.nodes[self.node].child[self.slot]) {
                break;
            }
        }
        self.leaf = if self.node / GROUP == group { self.leaf + 1 } else { 0 };
        self.off = 0;
    }
}

/// Nodes per group of [`store_leaves`].
const GROUP: usize = 1024;

fn is_leaf(child: u32) -> bool {
    child != EMPTY && child & LEAF_BIT != 0
}

/// The builder's (first, count) of a leaf child.
fn range_of(child: u32) -> (u32, u32) {
    let (first, count) = leaf_range(child);
    assert!(count <= LANES, "a leaf of {count} primitives does not fit one block");
    (first as u32, count as u32)
}

/// The builder's (first, count) of each leaf child of `nodes`, in node then slot order.
fn leaf_ranges(nodes: &[Node8]) -> impl Iterator<Item = (u32, u32)> + '_ {
    nodes.iter().flat_map(|n| n.child).filter(|&c| is_leaf(c)).map(range_of)
}

/// Calls `store` with each leaf child's (first, count) in node then slot order, and points
/// the child at the place in the store it returns.
fn for_each_leaf(nodes: &mut [Node8], mut store: impl FnMut(u32, u32) -> u32) {
    for node in nodes {
        for child in node.child.iter_mut().filter(|c| is_leaf(**c)) {
            let (first, count) = range_of(*child);
            *child = leaf_ref(store(first, count), count);
        }
    }
}

/// A leaf's packed record before it is written: its distinct vertices (mesh indices) and
/// each corner's place among them.
struct Packed {
    ids: [u32; LANES],
    tri_lanes: u32,
    /// Sphere lanes (padding lanes hold `u32::MAX`).
    other_lanes: u32,
    verts: [u32; 3 * LANES],
    nverts: usize,
    local: [u8; 3 * LANES],
}

impl Packed {
    fn of(ids: &[u32; LANES], corners: &[[u32; 3]; LANES], tri_count: u32) -> Packed {
        let mut p =
            Packed { ids: *ids, tri_lanes: 0, other_lanes: 0, verts: [0; 3 * LANES], nverts: 0, local: [0; 3 * LANES] };
        for lane in 0..LANES {
            if ids[lane] >= tri_count {
                p.other_lanes |= ((ids[lane] != u32::MAX) as u32) << lane;
                continue;
            }
            p.tri_lanes |= 1 << lane;
            for (k, &v) in corners[lane].iter().enumerate() {
                let at = p.verts[..p.nverts].iter().position(|&u| u == v).unwrap_or_else(|| {
                    p.verts[p.nverts] = v;
                    p.nverts += 1;
                    p.nverts - 1
                });
                p.local[3 * lane + k] = at as u8;
            }
        }
        // A leaf of spheres only still reads vertex 0 (masked out): keep one.
        p.nverts = p.nverts.max(1);
        p
    }

    fn lines(&self) -> usize {
        (PACKED_HEAD + 3 * self.nverts).div_ceil(16)
    }

    fn write(&self, out: &mut [u32], positions: &[Vec3]) {
        out[..LANES].copy_from_slice(&self.ids);
        let idx: [u32; 3] = bytemuck::cast(self.local);
        out[4..7].copy_from_slice(&idx);
        out[7] = self.tri_lanes | self.other_lanes << 4;
        for (i, &v) in self.verts[..self.nverts].iter().enumerate() {
            let p = if self.tri_lanes == 0 { Vec3::ZERO } else { positions[v as usize] };
            out[PACKED_HEAD + 3 * i..PACKED_HEAD + 3 * i + 3].copy_from_slice(&p.to_array().map(f32::to_bits));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A walk gives every unit's leaf and its place in the leaf, from a seek or by steps, as
    /// a plain listing of the leaf children in node and slot order does: over groups with
    /// and without leaves, empty and inner slots, leaves of one to three units.
    #[test]
    fn a_walk_finds_every_unit_from_anywhere() {
        let mut i = 0u64;
        let mut next = move || {
            i += 1;
            crate::sampling::splitmix64(i)
        };
        let blank = Node8 { b: [[0.0; WIDTH]; 6], child: [EMPTY; WIDTH], perm: [0; WIDTH] };
        let mut nodes = vec![blank; 5 * GROUP + 17];
        let (mut first, mut want, mut sizes) = (0u32, vec![], vec![vec![]; nodes.len().div_ceil(GROUP)]);
        for (n, node) in nodes.iter_mut().enumerate() {
            // The third group holds no leaf at all.
            let leafless = n / GROUP == 2;
            for slot in 0..WIDTH {
                node.child[slot] = match next() % 4 {
                    0 => EMPTY,
                    1 => 7,
                    _ if leafless => 7,
                    k => {
                        let count = (k as u32 + next() as u32) % 4 + 1;
                        let size = (next() % 3 + 1) as u8;
                        want.extend((0..size as usize).map(|off| (first, count, off)));
                        sizes[n / GROUP].push(size);
                        first += count;
                        leaf_ref(first - count, count)
                    }
                };
            }
        }
        let starts = group_starts(&sizes);
        assert!(sizes[2].is_empty() && want.len() > 4 * GROUP);
        let walk = || Walk::new(&nodes, &sizes, &starts);
        let mut w = walk();
        for (u, &unit) in want.iter().enumerate() {
            assert_eq!(w.unit(u), unit, "unit {u} by steps");
        }
        for u in (0..want.len()).step_by(5) {
            let mut w = walk();
            assert_eq!(w.unit(u), want[u], "unit {u} by a seek");
            if u + 1 < want.len() {
                assert_eq!(w.unit(u + 1), want[u + 1], "unit {} after a seek", u + 1);
            }
        }
    }
}
