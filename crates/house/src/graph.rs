//! The file-level import graph of one crate target, and its cycles.
//!
//! A node is a file, or the test code of a file (its `#[cfg(test)]` modules and items), so that
//! `use super::*` in a file's own `mod tests` is not an import of another file, and a test
//! module, which nothing imports, can close no cycle with the code it tests. An edge `a -> b`
//! means that code in `a` names an item defined in `b`: through a `use`, a path
//! (`crate::b::f`, `super::f`, `b::f`) or a name brought in by a glob. Names are followed through
//! re-exports to the file that defines them. A re-export of a module's own descendant
//! (`pub use io::Error` in `lib.rs`) is the module's facade, not a use, and adds no edge; the
//! root's and other modules' own items used by their children are edges like any other.

use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::parse::{Crate, ModId};

/// A node of the graph: a file, or that file's test code.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Node {
    /// The file.
    pub file: PathBuf,
    /// Whether this is the file's test code.
    pub test: bool,
}

/// The import graph of one crate target.
#[derive(Debug, Default)]
pub struct Graph {
    /// The nodes, sorted.
    pub nodes: Vec<Node>,
    /// `(from, to)` node indices -> the names that tie them, with the first line of each.
    pub edges: BTreeMap<(usize, usize), BTreeMap<String, u32>>,
}

/// What a name or path leads to.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Target {
    /// A module.
    Module(ModId),
    /// An item defined in the module.
    Item(ModId),
}

impl Graph {
    /// Builds the graph of a crate target.
    pub fn of(krate: &Crate) -> Graph {
        let mut nodes: Vec<Node> = Vec::new();
        for m in &krate.modules {
            let test_code = m.uses.iter().any(|u| u.test) || m.refs.iter().any(|r| r.test);
            for test in [m.test, test_code] {
                let node = Node {
                    file: m.file.clone(),
                    test,
                };
                if (test == m.test || test_code) && !nodes.contains(&node) {
                    nodes.push(node);
                }
            }
        }
        nodes.sort();
        let index = |file: &PathBuf, test: bool| {
            nodes
                .iter()
                .position(|n| n.file == *file && n.test == test)
                .unwrap_or(0)
        };
        let mut edges: BTreeMap<(usize, usize), BTreeMap<String, u32>> = BTreeMap::new();
        let resolver = Resolver { krate };
        for (id, m) in krate.modules.iter().enumerate() {
            let mut add = |test: bool, target: ModId, name: &str, line: u32| {
                let from = index(&m.file, m.test || test);
                let t = &krate.modules[target];
                let to = index(&t.file, t.test);
                if from != to {
                    edges
                        .entry((from, to))
                        .or_default()
                        .entry(name.to_string())
                        .or_insert(line);
                }
            };
            for u in &m.uses {
                match resolver.path(id, &u.path, false) {
                    Some((Target::Item(t), at)) => {
                        if u.public && resolver.within(t, id) {
                            continue;
                        }
                        let name = if u.name.is_none() {
                            format!("{}::*", u.path[at])
                        } else {
                            u.path[at].clone()
                        };
                        add(u.test, t, &name, u.line);
                    }
                    Some((Target::Module(_), _)) | None => {}
                }
            }
            for r in &m.refs {
                if r.path.len() == 1
                    && (m.defs.contains_key(&r.path[0]) || m.children.contains_key(&r.path[0]))
                {
                    continue;
                }
                if let Some((Target::Item(t), at)) = resolver.path(id, &r.path, true) {
                    add(r.test, t, &r.path[at], r.line);
                }
            }
        }
        Graph { nodes, edges }
    }

    /// The number of edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The strongly connected components with more than one node, each sorted, in node order.
    pub fn cycles(&self) -> Vec<Vec<usize>> {
        let mut successors = vec![Vec::new(); self.nodes.len()];
        for &(a, b) in self.edges.keys() {
            successors[a].push(b);
        }
        let mut sccs: Vec<Vec<usize>> = strongly_connected(&successors)
            .into_iter()
            .filter(|c| c.len() > 1)
            .collect();
        for c in &mut sccs {
            c.sort_unstable();
        }
        sccs.sort();
        sccs
    }
}

struct Resolver<'a> {
    krate: &'a Crate,
}

impl Resolver<'_> {
    /// Whether `m` is `ancestor` or inside it.
    fn within(&self, mut m: ModId, ancestor: ModId) -> bool {
        loop {
            if m == ancestor {
                return true;
            }
            match self.krate.modules[m].parent {
                Some(p) => m = p,
                None => return false,
            }
        }
    }

    /// Resolves a path written in module `m`: its target and the index of the segment that
    /// named the item. `None` for a path outside the crate.
    /// A single name (`item`) means an item, never a module (see [`Self::lookup`]).
    fn path(&self, m: ModId, path: &[String], item: bool) -> Option<(Target, usize)> {
        self.path_guarded(m, path, &mut Vec::new(), item)
    }

    fn path_guarded(
        &self,
        m: ModId,
        path: &[String],
        open: &mut Vec<(ModId, String)>,
        item: bool,
    ) -> Option<(Target, usize)> {
        let first = path.first()?;
        let (mut current, rest) = match first.as_str() {
            "crate" => (0, 1),
            "self" => (m, 1),
            "super" => {
                let mut current = m;
                let mut k = 0;
                while path.get(k).is_some_and(|s| s == "super") {
                    current = self.krate.modules[current].parent?;
                    k += 1;
                }
                (current, k)
            }
            "::" => return None,
            name => match self.lookup(m, name, open, m, item && path.len() == 1)? {
                Target::Item(t) => return Some((Target::Item(t), 0)),
                Target::Module(t) => (t, 1),
            },
        };
        for (k, seg) in path.iter().enumerate().skip(rest) {
            match self.lookup(current, seg, open, current, false) {
                Some(Target::Module(t)) => current = t,
                Some(Target::Item(t)) => return Some((Target::Item(t), k)),
                // Not found (a macro-made item, say): the module that should hold it.
                None => return Some((Target::Item(current), k)),
            }
        }
        Some((Target::Module(current), path.len() - 1))
    }

    /// What `name` means in module `m`: a child module, an item it defines, or what its `use`
    /// bindings (explicit first, then globs) lead to.
    ///
    /// `viewer` is the module that asks (another one when `m` is glob-imported): a private item or
    /// `use` of `m` is seen only from `m` itself and its descendants. An `item` (a name standing
    /// alone, not a path's prefix) is never a module: `use crate::cluster::{self}` and a glob
    /// bringing a function `cluster` can both be in scope, in Rust's two namespaces.
    fn lookup(
        &self,
        m: ModId,
        name: &str,
        open: &mut Vec<(ModId, String)>,
        viewer: ModId,
        item: bool,
    ) -> Option<Target> {
        let module = &self.krate.modules[m];
        let sees_private = self.within(viewer, m);
        if let Some(&child) = module.children.get(name).filter(|_| !item) {
            return Some(Target::Module(child));
        }
        if let Some(&public) = module.defs.get(name) {
            return (public || sees_private).then_some(Target::Item(m));
        }
        let visible = |u: &&crate::parse::Use| u.public || sees_private;
        let key = (m, name.to_string());
        if open.contains(&key) {
            return None;
        }
        open.push(key);
        let mut found = None;
        for u in module
            .uses
            .iter()
            .filter(visible)
            .filter(|u| u.name.as_deref() == Some(name))
        {
            match self.path_guarded(m, &u.path, open, false) {
                Some((Target::Module(_), _)) if item => {}
                Some((t, _)) => {
                    found = Some(t);
                    break;
                }
                None => {}
            }
        }
        if found.is_none() {
            for u in module
                .uses
                .iter()
                .filter(visible)
                .filter(|u| u.name.is_none())
            {
                if let Some((Target::Module(g), _)) = self.path_guarded(m, &u.path, open, false) {
                    if let Some(t) = self.lookup(g, name, open, m, item) {
                        found = Some(t);
                        break;
                    }
                }
            }
        }
        open.pop();
        found
    }
}

/// Tarjan's strongly connected components of a graph given by its successor lists.
pub fn strongly_connected(successors: &[Vec<usize>]) -> Vec<Vec<usize>> {
    struct State<'a> {
        successors: &'a [Vec<usize>],
        index: Vec<Option<usize>>,
        low: Vec<usize>,
        on_stack: Vec<bool>,
        stack: Vec<usize>,
        next: usize,
        out: Vec<Vec<usize>>,
    }
    fn visit(s: &mut State, v: usize) {
        s.index[v] = Some(s.next);
        s.low[v] = s.next;
        s.next += 1;
        s.stack.push(v);
        s.on_stack[v] = true;
        for k in 0..s.successors[v].len() {
            let w = s.successors[v][k];
            match s.index[w] {
                None => {
                    visit(s, w);
                    s.low[v] = s.low[v].min(s.low[w]);
                }
                Some(iw) if s.on_stack[w] => s.low[v] = s.low[v].min(iw),
                Some(_) => {}
            }
        }
        if Some(s.low[v]) == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack[w] = false;
                component.push(w);
                if w == v {
                    break;
                }
            }
            s.out.push(component);
        }
    }
    let n = successors.len();
    let mut s = State {
        successors,
        index: vec![None; n],
        low: vec![0; n],
        on_stack: vec![false; n],
        stack: Vec::new(),
        next: 0,
        out: Vec::new(),
    };
    for v in 0..n {
        if s.index[v].is_none() {
            visit(&mut s, v);
        }
    }
    s.out
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::parse::read_crate;

    fn graph(files: &[(&str, &str)]) -> Graph {
        let files: BTreeMap<PathBuf, String> = files
            .iter()
            .map(|(p, s)| (PathBuf::from(p), s.to_string()))
            .collect();
        let krate = read_crate(Path::new("src/lib.rs"), &|p: &Path| files.get(p).cloned());
        assert!(krate.problems.is_empty(), "{:?}", krate.problems);
        Graph::of(&krate)
    }

    /// The cycles as file names (`name [tests]` for test code).
    fn cycles(g: &Graph) -> Vec<Vec<String>> {
        g.cycles()
            .iter()
            .map(|c| {
                c.iter()
                    .map(|&n| {
                        let node = &g.nodes[n];
                        let file = node.file.display().to_string();
                        if node.test {
                            format!("{file} [tests]")
                        } else {
                            file
                        }
                    })
                    .collect()
            })
            .collect()
    }

    fn edge_names(g: &Graph, from: &str, to: &str) -> Vec<String> {
        let at = |f: &str| {
            g.nodes
                .iter()
                .position(|n| n.file == Path::new(f) && !n.test)
                .unwrap()
        };
        g.edges
            .get(&(at(from), at(to)))
            .map(|names| names.keys().cloned().collect())
            .unwrap_or_default()
    }

    #[test]
    fn tarjan_finds_components() {
        // 0 -> 1 -> 2 -> 0, 2 -> 3, 3 -> 4 -> 3, 5 alone.
        let succ = vec![vec![1], vec![2], vec![0, 3], vec![4], vec![3], vec![]];
        let mut sccs: Vec<Vec<usize>> = strongly_connected(&succ)
            .into_iter()
            .map(|mut c| {
                c.sort();
                c
            })
            .collect();
        sccs.sort();
        assert_eq!(sccs, vec![vec![0, 1, 2], vec![3, 4], vec![5]]);
    }

    #[test]
    fn a_known_cycle_is_found_with_the_names_that_tie_it() {
        let g = graph(&[
            ("src/lib.rs", "pub mod data; pub mod seeds; pub mod figures;"),
            ("src/data.rs", "pub struct Run; pub fn load() { let _ = crate::seeds::read_seeds(); }"),
            ("src/seeds.rs", "use crate::data::Run;\npub fn read_seeds() {}\npub fn label(r: &Run) { super::figures::variant_label(); }"),
            ("src/figures.rs", "use crate::data::{self, Run};\npub fn variant_label() { data::load(); }"),
        ]);
        assert_eq!(
            cycles(&g),
            vec![vec!["src/data.rs", "src/figures.rs", "src/seeds.rs"]]
        );
        assert_eq!(
            edge_names(&g, "src/data.rs", "src/seeds.rs"),
            ["read_seeds"]
        );
        assert_eq!(
            edge_names(&g, "src/seeds.rs", "src/figures.rs"),
            ["variant_label"]
        );
        assert_eq!(
            edge_names(&g, "src/figures.rs", "src/data.rs"),
            ["Run", "load"]
        );
    }

    #[test]
    fn an_acyclic_crate_passes() {
        let g = graph(&[
            (
                "src/lib.rs",
                "pub mod a; pub mod b; pub mod c; pub use a::A; pub struct Top;",
            ),
            (
                "src/a.rs",
                "use crate::b::B; use crate::Top; pub struct A(B, Top);",
            ),
            ("src/b.rs", "pub struct B(crate::c::C);"),
            ("src/c.rs", "pub struct C;"),
        ]);
        assert!(cycles(&g).is_empty());
        assert_eq!(edge_names(&g, "src/a.rs", "src/b.rs"), ["B"]);
        assert_eq!(
            edge_names(&g, "src/a.rs", "src/lib.rs"),
            ["Top"],
            "the root's own items are imports"
        );
        assert_eq!(edge_names(&g, "src/b.rs", "src/c.rs"), ["C"]);
        assert!(
            edge_names(&g, "src/lib.rs", "src/a.rs").is_empty(),
            "a facade re-export is no import"
        );
    }

    #[test]
    fn a_root_that_uses_a_child_which_uses_the_root_is_a_cycle() {
        let g = graph(&[
            (
                "src/lib.rs",
                "mod io; pub struct Mesh; pub fn save(m: &Mesh) { io::write(m) }",
            ),
            ("src/io.rs", "use crate::Mesh; pub fn write(m: &Mesh) {}"),
        ]);
        assert_eq!(cycles(&g), vec![vec!["src/io.rs", "src/lib.rs"]]);
    }

    #[test]
    fn tests_importing_their_own_file_or_others_close_no_cycle() {
        let g = graph(&[
            ("src/lib.rs", "pub mod a; pub mod b;"),
            (
                "src/a.rs",
                "pub fn f() {}\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use crate::b::g;\n    #[test]\n    fn t() { f(); g(); }\n}",
            ),
            ("src/b.rs", "pub fn g() { crate::a::f() }\n#[cfg(test)]\nfn helper() { crate::a::f() }"),
        ]);
        assert!(cycles(&g).is_empty(), "{:?}", cycles(&g));
        let test_node = g
            .nodes
            .iter()
            .position(|n| n.file == Path::new("src/a.rs") && n.test)
            .unwrap();
        let b = g
            .nodes
            .iter()
            .position(|n| n.file == Path::new("src/b.rs") && !n.test)
            .unwrap();
        assert!(
            g.edges.contains_key(&(test_node, b)),
            "the test module's import is kept, from the test node"
        );
    }

    #[test]
    fn globs_count_only_the_names_used_and_follow_them_to_their_definition() {
        // `layout` takes `super::*` but only uses a name that `mt` itself imports from `lattice`:
        // an import of lattice, not of mt. `mt` uses `Layout` through its glob re-export.
        let g = graph(&[
            ("src/lib.rs", "pub mod lattice; pub mod mt;"),
            ("src/lattice.rs", "pub struct Tables;"),
            ("src/mt/mod.rs", "use crate::lattice::Tables;\nmod layout;\npub(crate) use layout::*;\npub fn overwritten() {}\npub fn run(l: Layout) {}"),
            ("src/mt/layout.rs", "use super::*;\npub struct Layout(Tables);"),
        ]);
        assert!(cycles(&g).is_empty(), "{:?}", cycles(&g));
        assert_eq!(
            edge_names(&g, "src/mt/layout.rs", "src/lattice.rs"),
            ["Tables"]
        );
        assert_eq!(
            edge_names(&g, "src/mt/mod.rs", "src/mt/layout.rs"),
            ["Layout"]
        );
        // Once layout calls a function defined in mt, the two form a cycle.
        let g = graph(&[
            ("src/lib.rs", "pub mod mt;"),
            ("src/mt/mod.rs", "mod layout;\npub(crate) use layout::*;\npub fn overwritten() {}\npub fn run(l: Layout) {}"),
            ("src/mt/layout.rs", "use super::*;\npub struct Layout;\nfn f() { overwritten() }"),
        ]);
        assert_eq!(cycles(&g), vec![vec!["src/mt/layout.rs", "src/mt/mod.rs"]]);
    }

    #[test]
    fn globs_see_private_items_only_from_below_and_locals_are_not_items() {
        let g = graph(&[
            ("src/lib.rs", "mod mt;"),
            ("src/mt/mod.rs", "mod emission; mod integrated; use emission::*; use integrated::*; pub fn run() {}"),
            ("src/mt/integrated.rs", "fn count() {} pub(crate) fn total() {} fn f() { count(); }"),
            (
                "src/mt/emission.rs",
                "use super::*;\npub fn e(first: usize) { let count = 3; for total in 0..count { run(); } }\n\
                 pub fn h(v: &[u8]) { v.iter().map(|x| x + 1); }",
            ),
        ]);
        assert!(edge_names(&g, "src/mt/emission.rs", "src/mt/integrated.rs").is_empty());
        assert_eq!(
            edge_names(&g, "src/mt/emission.rs", "src/mt/mod.rs"),
            ["run"]
        );
    }

    #[test]
    fn a_module_and_a_function_of_one_name_live_in_two_namespaces() {
        let g = graph(&[
            ("src/lib.rs", "mod cluster; mod mt;"),
            ("src/cluster.rs", "pub struct Rules;"),
            ("src/mt/mod.rs", "use crate::cluster::{self, Rules};\nmod integrated;\nuse integrated::*;\nfn run(r: Rules) { cluster(r) }"),
            ("src/mt/integrated.rs", "pub(crate) fn cluster(r: crate::cluster::Rules) {}"),
        ]);
        assert_eq!(
            edge_names(&g, "src/mt/mod.rs", "src/mt/integrated.rs"),
            ["cluster"]
        );
        assert_eq!(edge_names(&g, "src/mt/mod.rs", "src/cluster.rs"), ["Rules"]);
    }

    #[test]
    fn mutual_globs_terminate() {
        let g = graph(&[
            ("src/lib.rs", "mod a; mod b;"),
            ("src/a.rs", "pub use crate::b::*; fn f() { nowhere() }"),
            ("src/b.rs", "pub use crate::a::*; fn g() { elsewhere() }"),
        ]);
        assert!(cycles(&g).is_empty());
    }
}
