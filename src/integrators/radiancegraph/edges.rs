//! Per-node edge lists in size-class slabs: the graph's edges while it is built and, with the
//! counts turned into weights in place, the transport matrix T (Eq. 4.8) it is solved with.
//!
//! A node's list lives in one slot of the pool for its capacity class (1, 2, 4, … entries);
//! when full it moves to a slot of the next class and its old slot is reused by the next
//! list that grows into that class. Pools grow in fixed chunks, so nothing is ever copied
//! wholesale and no allocation holds twice its contents. An entry is 8 bytes (target node,
//! count or weight); a list uses at most twice its length, about 1.3× on average.

/// Entries per pool chunk (at least one slot of the class).
const CHUNK: usize = 1 << 16;

/// One edge: the node it leads to and its sample count, or after [`EdgeLists::into_weights`]
/// its weight's bits.
type Entry = (u32, u32);

#[derive(Default)]
struct Pool {
    chunks: Vec<Box<[Entry]>>,
    /// Slots handed out so far.
    slots: u32,
    /// Slots given back, reused first.
    free: Vec<u32>,
}

/// Edge lists for every node.
#[derive(Default)]
pub struct EdgeLists {
    /// Per node: slot in its class's pool and list length (the class follows from the length).
    rows: Vec<(u32, u32)>,
    pools: Vec<Pool>,
    edges: usize,
}

#[inline]
fn class_of(len: u32) -> usize {
    len.max(1).next_power_of_two().trailing_zeros() as usize
}

impl EdgeLists {
    /// Adds an empty list (a new node).
    pub fn push_node(&mut self) {
        self.rows.push((u32::MAX, 0));
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.rows.len()
    }

    /// Number of edges.
    pub fn edges(&self) -> usize {
        self.edges
    }

    /// Length of node `a`'s list.
    pub fn len(&self, a: u32) -> usize {
        self.rows[a as usize].1 as usize
    }

    /// True when no node has an edge.
    pub fn is_empty(&self) -> bool {
        self.edges == 0
    }

    fn slot_range(class: usize, slot: u32) -> (usize, usize) {
        let cap = 1usize << class;
        let per_chunk = CHUNK.max(cap) / cap;
        (slot as usize / per_chunk, slot as usize % per_chunk * cap)
    }

    fn slice(&self, class: usize, slot: u32, len: usize) -> &[Entry] {
        let (c, o) = Self::slot_range(class, slot);
        &self.pools[class].chunks[c][o..o + len]
    }

    fn slice_mut(&mut self, class: usize, slot: u32, len: usize) -> &mut [Entry] {
        let (c, o) = Self::slot_range(class, slot);
        &mut self.pools[class].chunks[c][o..o + len]
    }

    fn alloc(&mut self, class: usize) -> u32 {
        if self.pools.len() <= class {
            self.pools.resize_with(class + 1, Pool::default);
        }
        let cap = 1usize << class;
        let per_chunk = CHUNK.max(cap) / cap;
        let pool = &mut self.pools[class];
        if let Some(s) = pool.free.pop() {
            return s;
        }
        let s = pool.slots;
        if (s as usize).is_multiple_of(per_chunk) {
            pool.chunks.push(vec![(0, 0); per_chunk * cap].into_boxed_slice());
        }
        pool.slots += 1;
        s
    }

    /// The entries of node `a`: (target, count or weight bits).
    pub fn row(&self, a: u32) -> &[Entry] {
        let (slot, len) = self.rows[a as usize];
        if len == 0 { &[] } else { self.slice(class_of(len), slot, len as usize) }
    }

    /// Counts one more sample of edge `from` → `to`.
    pub fn add(&mut self, from: u32, to: u32) {
        let (slot, len) = self.rows[from as usize];
        if len > 0 {
            let class = class_of(len);
            if let Some(e) = self.slice_mut(class, slot, len as usize).iter_mut().find(|e| e.0 == to) {
                e.1 += 1;
                return;
            }
        }
        // A new edge: grow into the next class when the slot is full.
        let new_len = len + 1;
        let (old_class, new_class) = (class_of(len), class_of(new_len));
        let slot = if len == 0 {
            self.alloc(new_class)
        } else if new_class != old_class {
            let s = self.alloc(new_class);
            let (oc, oo) = Self::slot_range(old_class, slot);
            let (nc, no) = Self::slot_range(new_class, s);
            for i in 0..len as usize {
                let e = self.pools[old_class].chunks[oc][oo + i];
                self.pools[new_class].chunks[nc][no + i] = e;
            }
            self.pools[old_class].free.push(slot);
            s
        } else {
            slot
        };
        self.slice_mut(new_class, slot, new_len as usize)[len as usize] = (to, 1);
        self.rows[from as usize] = (slot, new_len);
        self.edges += 1;
    }

    /// Bytes held, as (the per-node row table, the pools with their free lists).
    pub fn memory_bytes(&self) -> (usize, usize) {
        let pools: usize = self
            .pools
            .iter()
            .map(|p| p.chunks.iter().map(|c| c.len() * 8).sum::<usize>() + p.free.capacity() * 4)
            .sum();
        (self.rows.capacity() * 8, pools)
    }

    /// Edges sampled more than once.
    pub fn more_than_once(&self) -> usize {
        (0..self.rows.len() as u32).map(|a| self.row(a).iter().filter(|e| e.1 > 1).count()).sum()
    }

    /// Turns each count s_e(a, b) into the weight s_e(a, b) / s_n(a) (Eq. 4.20), in place.
    pub fn into_weights(mut self, node_samples: &[u32]) -> EdgeLists {
        for (a, &samples) in node_samples.iter().enumerate() {
            let (slot, len) = self.rows[a];
            if len == 0 {
                continue;
            }
            let s = samples as f32;
            for e in self.slice_mut(class_of(len), slot, len as usize) {
                e.1 = (e.1 as f32 / s).to_bits();
            }
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_grow_and_reuse_slots() {
        let mut l = EdgeLists::default();
        for _ in 0..3 {
            l.push_node();
        }
        for to in 0..5 {
            l.add(0, to);
        }
        l.add(0, 3);
        l.add(1, 7);
        l.add(1, 8);
        assert_eq!(l.row(0), [(0, 1), (1, 1), (2, 1), (3, 2), (4, 1)]);
        assert_eq!(l.row(1), [(7, 1), (8, 1)]);
        assert!(l.row(2).is_empty());
        assert_eq!((l.edges(), l.more_than_once()), (7, 1));
        // Node 0 passed through classes 0, 1 and 2 and now sits in class 3; node 1 took
        // the freed class-0 slot first and then class 1's.
        assert_eq!(l.pools[0].free.len() + l.pools[1].free.len() + l.pools[2].free.len(), 2);
        let w = l.into_weights(&[10, 4, 0]);
        assert_eq!(f32::from_bits(w.row(0)[3].1), 0.2);
        assert_eq!(f32::from_bits(w.row(1)[0].1), 0.25);
    }

    /// Lists longer than a chunk get a chunk of their own.
    #[test]
    fn long_lists() {
        let mut l = EdgeLists::default();
        l.push_node();
        let n = CHUNK as u32 + 10;
        for to in 0..n {
            l.add(0, to);
        }
        assert_eq!(l.len(0), n as usize);
        assert!(l.row(0).iter().enumerate().all(|(i, e)| e.0 == i as u32));
    }
}
