//! Phase 3 of resolution: the pass DAG. An edge runs from each writer of a resource to
//! each of its readers and from each pass named in `after` to the pass naming it. Reading
//! what nobody writes, reading and writing one resource, cycles (named pass by pass) and
//! writers of one resource that the DAG leaves unordered are errors found here.

use std::collections::{BTreeSet, HashMap};

use petgraph::graph::{DiGraph, NodeIndex};

use super::bind::RawBinding;
use super::ctx::Ctx;
use super::resolved::Dependency;
use crate::error::{GraphError, suggest};
use crate::kinds::Access;

/// The DAG of every declared pass, with who writes what.
pub(super) struct Dag {
    /// Node weight: pass name; edge weight: why the edge exists.
    pub(super) graph: DiGraph<String, Dependency>,
    /// Node of each pass, by pass index.
    pub(super) nodes: Vec<NodeIndex>,
    /// Passes writing each resource, by resource declaration index.
    pub(super) writers: Vec<Vec<usize>>,
    /// Whether a cycle was found (then nothing can be scheduled).
    pub(super) cyclic: bool,
}

impl Ctx<'_> {
    /// Builds the DAG from the bindings and `after` lists and checks it.
    pub(super) fn build_dag(
        &mut self,
        bindings: &[Vec<RawBinding>],
        pass_index: &HashMap<&str, usize>,
    ) -> Dag {
        let mut graph: DiGraph<String, Dependency> = DiGraph::new();
        let nodes: Vec<NodeIndex> = self
            .desc
            .passes
            .iter()
            .map(|p| graph.add_node(p.name.clone()))
            .collect();
        let mut dag = Dag {
            graph,
            nodes,
            writers: Vec::new(),
            cyclic: false,
        };
        self.resource_edges(&mut dag, bindings);
        self.after_edges(&mut dag, pass_index);
        self.find_cycles(&mut dag);
        if !dag.cyclic {
            self.check_writer_order(&dag);
        }
        dag
    }

    /// Writer → reader edges for every resource; fills `dag.writers`.
    fn resource_edges(&mut self, dag: &mut Dag, bindings: &[Vec<RawBinding>]) {
        let desc = self.desc;
        let nres = desc.resources.0.len();
        let mut writers: Vec<Vec<usize>> = vec![Vec::new(); nres];
        let mut readers: Vec<Vec<usize>> = vec![Vec::new(); nres];
        for (pi, bs) in bindings.iter().enumerate() {
            for b in bs {
                match b.slot.access {
                    Access::Write => writers[b.resource].push(pi),
                    Access::Read => readers[b.resource].push(pi),
                }
            }
        }
        for r in 0..nres {
            writers[r].dedup();
            readers[r].dedup();
            let name = &desc.resources.0[r].0;
            for &rd in &readers[r] {
                if writers[r].contains(&rd) {
                    self.errors.push(GraphError::ReadWriteSame {
                        at: self.at(self.loc.in_pass(&desc.passes[rd].name, name)),
                        pass: desc.passes[rd].name.clone(),
                        resource: name.clone(),
                    });
                    continue;
                }
                if writers[r].is_empty() {
                    self.errors.push(GraphError::NoProducer {
                        at: self.at(self.loc.in_pass(&desc.passes[rd].name, name)),
                        pass: desc.passes[rd].name.clone(),
                        resource: name.clone(),
                    });
                }
                for &w in &writers[r] {
                    dag.graph.update_edge(
                        dag.nodes[w],
                        dag.nodes[rd],
                        Dependency::Resource(name.clone()),
                    );
                }
            }
        }
        dag.writers = writers;
    }

    /// Edges for `after`; names that are no pass are errors.
    fn after_edges(&mut self, dag: &mut Dag, pass_index: &HashMap<&str, usize>) {
        let desc = self.desc;
        for (pi, p) in desc.passes.iter().enumerate() {
            for a in &p.after {
                match pass_index.get(a.as_str()) {
                    Some(&ai) => {
                        dag.graph
                            .update_edge(dag.nodes[ai], dag.nodes[pi], Dependency::After);
                    }
                    None => self.errors.push(GraphError::UnknownAfter {
                        at: self.at(self.loc.in_pass(&p.name, a)),
                        pass: p.name.clone(),
                        after: a.clone(),
                        hint: suggest(a, desc.passes.iter().map(|p| p.name.as_str())),
                    }),
                }
            }
        }
    }

    /// Cycles: every strongly connected component with more than one pass, or a self loop.
    fn find_cycles(&mut self, dag: &mut Dag) {
        for scc in petgraph::algo::tarjan_scc(&dag.graph) {
            let self_loop = scc.len() == 1 && dag.graph.find_edge(scc[0], scc[0]).is_some();
            if scc.len() > 1 || self_loop {
                dag.cyclic = true;
                let cycle = find_cycle(&dag.graph, &scc);
                let first = cycle[0].clone();
                self.errors.push(GraphError::Cycle {
                    at: self.at(self.loc.pass(&first)),
                    cycle,
                });
            }
        }
    }

    /// Writers of one resource must be ordered (only meaningful without cycles).
    fn check_writer_order(&mut self, dag: &Dag) {
        let desc = self.desc;
        let (graph, nodes) = (&dag.graph, &dag.nodes);
        for (r, w) in dag.writers.iter().enumerate() {
            for i in 0..w.len() {
                for j in i + 1..w.len() {
                    let (a, b) = (nodes[w[i]], nodes[w[j]]);
                    if !petgraph::algo::has_path_connecting(graph, a, b, None)
                        && !petgraph::algo::has_path_connecting(graph, b, a, None)
                    {
                        let second = &desc.passes[w[j]].name;
                        self.errors.push(GraphError::UnorderedWriters {
                            at: self.at(self.loc.in_pass(second, &desc.resources.0[r].0)),
                            resource: desc.resources.0[r].0.clone(),
                            first: desc.passes[w[i]].name.clone(),
                            second: second.clone(),
                        });
                    }
                }
            }
        }
    }
}

/// One simple cycle inside a strongly connected component, as pass names, closed
/// (the first name repeated at the end).
fn find_cycle(dag: &DiGraph<String, Dependency>, scc: &[NodeIndex]) -> Vec<String> {
    let inside: BTreeSet<NodeIndex> = scc.iter().copied().collect();
    let start = *scc.iter().min().expect("non-empty component");
    // Breadth-first search from `start` back to `start` inside the component.
    let mut prev: HashMap<NodeIndex, NodeIndex> = HashMap::new();
    let mut queue = std::collections::VecDeque::from([start]);
    let mut end = None;
    'bfs: while let Some(n) = queue.pop_front() {
        let mut next: Vec<NodeIndex> = dag.neighbors(n).filter(|m| inside.contains(m)).collect();
        next.sort();
        for m in next {
            if m == start {
                end = Some(n);
                break 'bfs;
            }
            if let std::collections::hash_map::Entry::Vacant(e) = prev.entry(m) {
                e.insert(n);
                queue.push_back(m);
            }
        }
    }
    let mut path = vec![start];
    let mut n = end.unwrap_or(start);
    let mut back = Vec::new();
    while n != start {
        back.push(n);
        n = prev[&n];
    }
    path.extend(back.into_iter().rev());
    path.push(start);
    path.into_iter().map(|n| dag[n].clone()).collect()
}
