//! Phases 4 and 5 of resolution: what the pipeline must produce (the `output` and the
//! resources in `keep`), the passes that contribute to it (everything else is pruned) and
//! their order: a topological sort in which file order breaks ties, so that a schedule
//! does not change unless the file does.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use petgraph::visit::EdgeRef;

use super::bind::RawBinding;
use super::ctx::Ctx;
use super::dag::Dag;
use super::resolved::Dependency;
use crate::error::{GraphError, suggest};
use crate::schema::ResourceDesc;

/// What the pipeline must produce, as resource declaration indices.
pub(super) struct Roots {
    /// The output, if it is a declared texture that some pass writes.
    pub(super) output: Option<usize>,
    /// The resources in `keep` that some pass writes.
    pub(super) kept: Vec<usize>,
}

impl Ctx<'_> {
    /// Checks the `output` and `keep` resources: declared, written, the output a texture.
    pub(super) fn roots(
        &mut self,
        res_index: &HashMap<&str, usize>,
        writers: &[Vec<usize>],
    ) -> Roots {
        let output = self.check_output(res_index, writers);
        let kept = self.check_kept(res_index, writers);
        Roots { output, kept }
    }

    /// The `output`: a declared texture that some pass writes.
    fn check_output(
        &mut self,
        res_index: &HashMap<&str, usize>,
        writers: &[Vec<usize>],
    ) -> Option<usize> {
        let desc = self.desc;
        let out_at = self.at(self.loc.output());
        match res_index.get(desc.output.as_str()) {
            None => {
                self.errors.push(GraphError::BadOutput {
                    at: out_at,
                    output: desc.output.clone(),
                    message: format!(
                        "is not a declared resource{}",
                        suggest(
                            &desc.output,
                            desc.resources.0.iter().map(|(n, _)| n.as_str())
                        )
                    ),
                });
                None
            }
            Some(&o) => {
                if !matches!(desc.resources.0[o].1, ResourceDesc::Texture { .. }) {
                    self.errors.push(GraphError::BadOutput {
                        at: out_at,
                        output: desc.output.clone(),
                        message: "must be a texture".to_string(),
                    });
                    None
                } else if writers[o].is_empty() {
                    self.errors.push(GraphError::BadOutput {
                        at: out_at,
                        output: desc.output.clone(),
                        message: "is written by no pass".to_string(),
                    });
                    None
                } else {
                    Some(o)
                }
            }
        }
    }

    /// The resources in `keep`: declared and written by some pass.
    fn check_kept(
        &mut self,
        res_index: &HashMap<&str, usize>,
        writers: &[Vec<usize>],
    ) -> Vec<usize> {
        let desc = self.desc;
        let mut kept = Vec::new();
        for k in &desc.keep {
            match res_index.get(k.as_str()) {
                Some(&r) if !writers[r].is_empty() => kept.push(r),
                Some(_) => self.errors.push(GraphError::BadOutput {
                    at: self.at(self.loc.resource_declarations(k).last().copied()),
                    output: k.clone(),
                    message: "is kept but written by no pass".to_string(),
                }),
                None => self.errors.push(GraphError::BadOutput {
                    at: self.at(self.loc.output()),
                    output: k.clone(),
                    message: format!(
                        "(in `keep`) is not a declared resource{}",
                        suggest(k, desc.resources.0.iter().map(|(n, _)| n.as_str()))
                    ),
                }),
            }
        }
        kept
    }

    /// Names of the passes that do not contribute to the output, in file order.
    pub(super) fn pruned_passes(&self, live: &[bool]) -> Vec<String> {
        let desc = self.desc;
        (0..desc.passes.len())
            .filter(|&p| !live[p])
            .map(|p| desc.passes[p].name.clone())
            .collect()
    }
}

impl Dag {
    /// Prune: a pass is live if it writes the output, or writes a resource a live pass
    /// touches, or a live pass runs after it (explicit ordering is a promise of effect).
    /// Returns liveness by pass index.
    pub(super) fn live(
        &self,
        bindings: &[Vec<RawBinding>],
        output: usize,
        kept: &[usize],
    ) -> Vec<bool> {
        let writers = &self.writers;
        let mut live = vec![false; bindings.len()];
        let mut stack: Vec<usize> = writers[output].clone();
        for &k in kept {
            stack.extend(writers[k].iter().copied());
        }
        while let Some(p) = stack.pop() {
            if std::mem::replace(&mut live[p], true) {
                continue;
            }
            for b in &bindings[p] {
                stack.extend(writers[b.resource].iter().copied().filter(|&w| !live[w]));
            }
            for e in self
                .graph
                .edges_directed(self.nodes[p], petgraph::Direction::Incoming)
            {
                if e.weight() == &Dependency::After && !live[e.source().index()] {
                    stack.push(e.source().index());
                }
            }
        }
        live
    }

    /// Schedule: Kahn's algorithm over live passes, smallest file index first. Returns
    /// pass indices in execution order.
    pub(super) fn schedule(&self, live: &[bool]) -> Vec<usize> {
        let n = live.len();
        let mut indeg = vec![0usize; n];
        for e in self.graph.edge_references() {
            if live[e.source().index()] && live[e.target().index()] {
                indeg[e.target().index()] += 1;
            }
        }
        let mut heap: BinaryHeap<Reverse<usize>> = (0..n)
            .filter(|&p| live[p] && indeg[p] == 0)
            .map(Reverse)
            .collect();
        let mut order = Vec::new();
        while let Some(Reverse(p)) = heap.pop() {
            order.push(p);
            for e in self
                .graph
                .edges_directed(self.nodes[p], petgraph::Direction::Outgoing)
            {
                let t = e.target().index();
                if live[t] {
                    indeg[t] -= 1;
                    if indeg[t] == 0 {
                        heap.push(Reverse(t));
                    }
                }
            }
        }
        order
    }
}
