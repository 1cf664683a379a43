//! The module tree of one crate target, read from its source files: for every module (a file or
//! an inline `mod x { .. }`), its child modules, the names it defines, its `use` bindings and the
//! paths and names its code mentions. Test code (`#[cfg(test)]` items and modules) is marked, so
//! that the graph can keep it apart.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::lex::{lex, Tok, Token};

/// An index into [`Crate::modules`].
pub type ModId = usize;

/// The modules of one crate target; the root (`lib.rs`, `main.rs`, a test or an example) is
/// module 0.
#[derive(Debug, Default)]
pub struct Crate {
    /// Every module, the root first.
    pub modules: Vec<Module>,
    /// Module files that were declared but could not be read (`mod x;` without `x.rs`).
    pub problems: Vec<String>,
}

/// One module.
#[derive(Debug)]
pub struct Module {
    /// Its name (`crate` for the root).
    pub name: String,
    /// The module that declares it.
    pub parent: Option<ModId>,
    /// The file its code is in (an inline module shares its parent's file).
    pub file: PathBuf,
    /// Whether it exists only under `#[cfg(test)]`.
    pub test: bool,
    /// Its child modules by name.
    pub children: BTreeMap<String, ModId>,
    /// The names of the items it defines (functions, types, traits, constants, macros), each
    /// with whether it is visible outside the module (`pub` of any kind; a glob import from
    /// another part of the crate sees only those).
    pub defs: BTreeMap<String, bool>,
    /// Its `use` bindings, in order.
    pub uses: Vec<Use>,
    /// The paths (`a::b::c`) and single names its code mentions.
    pub refs: Vec<Ref>,
}

/// One binding made by a `use` declaration.
#[derive(Clone, Debug, PartialEq)]
pub struct Use {
    /// The name bound (`None` for a glob `*`).
    pub name: Option<String>,
    /// The path as written (`crate`, `self` and `super` included; `self` leaves removed).
    pub path: Vec<String>,
    /// Whether it is a re-export (`pub`, `pub(crate)`, ...).
    pub public: bool,
    /// Whether it is test code.
    pub test: bool,
    /// The line it is on.
    pub line: u32,
}

/// A path or single name mentioned by code.
#[derive(Clone, Debug, PartialEq)]
pub struct Ref {
    /// The segments (one for a single name).
    pub path: Vec<String>,
    /// Whether it is in test code.
    pub test: bool,
    /// The line it is on.
    pub line: u32,
}

/// Reads the crate target whose root file is `root`; `read` returns a file's text (or `None`).
pub fn read_crate(root: &Path, read: &dyn Fn(&Path) -> Option<String>) -> Crate {
    let mut walker = Walker {
        read,
        krate: Crate::default(),
        open: Vec::new(),
    };
    match read(root) {
        Some(src) => {
            let dir = root.parent().unwrap_or(Path::new("")).to_path_buf();
            walker.file_module(root, "crate", None, false, &src, dir);
        }
        None => walker
            .krate
            .problems
            .push(format!("cannot read {}", root.display())),
    }
    walker.krate
}

struct Walker<'a> {
    read: &'a dyn Fn(&Path) -> Option<String>,
    krate: Crate,
    /// The files being read (a `#[path]` loop stops here).
    open: Vec<PathBuf>,
}

/// Where a module body's `mod x;` declarations look for files.
struct Dirs {
    /// The directory of `x.rs` and `x/mod.rs`.
    children: PathBuf,
    /// The directory a `#[path = ".."]` is relative to.
    path_attr: PathBuf,
}

impl Walker<'_> {
    fn new_module(&mut self, name: &str, parent: Option<ModId>, file: &Path, test: bool) -> ModId {
        let id = self.krate.modules.len();
        self.krate.modules.push(Module {
            name: name.to_string(),
            parent,
            file: file.to_path_buf(),
            test,
            children: BTreeMap::new(),
            defs: BTreeMap::new(),
            uses: Vec::new(),
            refs: Vec::new(),
        });
        if let Some(p) = parent {
            self.krate.modules[p].children.insert(name.to_string(), id);
        }
        id
    }

    /// A module whose body is the whole of `file`; `children_dir` is where its `mod x;` look.
    fn file_module(
        &mut self,
        file: &Path,
        name: &str,
        parent: Option<ModId>,
        test: bool,
        src: &str,
        children_dir: PathBuf,
    ) -> ModId {
        let id = self.new_module(name, parent, file, test);
        self.open.push(file.to_path_buf());
        let toks = lex(src);
        let mut pos = 0;
        let dirs = Dirs {
            children: children_dir,
            path_attr: file.parent().unwrap_or(Path::new("")).to_path_buf(),
        };
        self.items(&toks, &mut pos, id, &dirs);
        self.open.pop();
        id
    }

    /// Reads items until the `}` that closes the module body (or the end of the file).
    fn items(&mut self, toks: &[Token], pos: &mut usize, m: ModId, dirs: &Dirs) {
        while *pos < toks.len() {
            let t = &toks[*pos].tok;
            if t.is('}') {
                *pos += 1;
                return;
            }
            if t.is(';') {
                *pos += 1;
                continue;
            }
            let mut test = self.krate.modules[m].test;
            let mut path_attr = None;
            while *pos < toks.len() && toks[*pos].tok.is('#') {
                let inner = toks.get(*pos + 1).is_some_and(|t| t.tok.is('!'));
                let open = *pos + 1 + usize::from(inner);
                if !toks.get(open).is_some_and(|t| t.tok.is('[')) {
                    break;
                }
                let close = matching(toks, open);
                let attr = &toks[open + 1..close.min(toks.len())];
                if is_cfg_test(attr) {
                    if inner {
                        self.krate.modules[m].test = true;
                    }
                    test = true;
                }
                if let Some(p) = path_attribute(attr) {
                    path_attr = Some(p);
                }
                *pos = close + 1;
            }
            if *pos >= toks.len() {
                return;
            }
            let mut public = false;
            if toks[*pos].tok.is_word("pub") {
                public = true;
                *pos += 1;
                if toks.get(*pos).is_some_and(|t| t.tok.is('(')) {
                    *pos = matching(toks, *pos) + 1;
                }
            }
            while let Some(w) = toks.get(*pos).and_then(|t| t.tok.ident()) {
                let extern_abi = w == "extern"
                    && matches!(toks.get(*pos + 1).map(|t| &t.tok), Some(Tok::Str(_)));
                if matches!(w, "unsafe" | "async" | "default" | "auto") {
                    *pos += 1;
                } else if extern_abi {
                    *pos += 2;
                } else {
                    break;
                }
            }
            let word = toks.get(*pos).and_then(|t| t.tok.ident()).unwrap_or("");
            let next = |k: usize| toks.get(*pos + k).map(|t| &t.tok);
            match word {
                "mod" => {
                    let Some(name) = next(1).and_then(Tok::ident).map(str::to_string) else {
                        *pos += 1;
                        continue;
                    };
                    if next(2).is_some_and(|t| t.is('{')) {
                        *pos += 3;
                        let file = self.krate.modules[m].file.clone();
                        let child = self.new_module(&name, Some(m), &file, test);
                        let inner = Dirs {
                            children: dirs.children.join(&name),
                            path_attr: dirs.children.join(&name),
                        };
                        self.items(toks, pos, child, &inner);
                    } else {
                        *pos += 3;
                        self.declared_file(&name, m, test, path_attr, dirs);
                    }
                }
                "use" => {
                    *pos += 1;
                    let line = toks[*pos - 1].line;
                    let mut bound = Vec::new();
                    use_tree(toks, pos, Vec::new(), &mut bound);
                    while *pos < toks.len() && !toks[*pos].tok.is(';') {
                        *pos += 1;
                    }
                    *pos += 1;
                    let module = &mut self.krate.modules[m];
                    for (name, path) in bound {
                        module.uses.push(Use {
                            name,
                            path,
                            public,
                            test,
                            line,
                        });
                    }
                }
                "macro_rules" => {
                    if let Some(name) = next(2).and_then(Tok::ident) {
                        self.krate.modules[m].defs.insert(name.to_string(), true);
                    }
                    // Paths inside a macro's body resolve where it is expanded: not read here.
                    let end = item_end(toks, *pos, false);
                    *pos = end;
                }
                _ => {
                    let (def, semicolon_only) = match word {
                        "fn" | "struct" | "enum" | "union" | "trait" | "type" => {
                            (next(1), word == "type")
                        }
                        "static" if next(1).is_some_and(|t| t.is_word("mut")) => (next(2), true),
                        "const" if next(1).is_some_and(|t| t.is_word("fn")) => (next(2), false),
                        "static" | "const" => (next(1), true),
                        _ => (None, false),
                    };
                    if let Some(name) = def.and_then(Tok::ident).filter(|n| *n != "_") {
                        self.krate.modules[m].defs.insert(name.to_string(), public);
                    }
                    let end = item_end(toks, *pos, semicolon_only);
                    self.code(&toks[*pos..end], m, test);
                    *pos = end;
                }
            }
        }
    }

    /// `mod name;`: reads `name.rs`, `name/mod.rs` or the `#[path]` file.
    fn declared_file(
        &mut self,
        name: &str,
        m: ModId,
        test: bool,
        path_attr: Option<String>,
        dirs: &Dirs,
    ) {
        let candidates = match &path_attr {
            Some(p) => vec![dirs.path_attr.join(p)],
            None => vec![
                dirs.children.join(format!("{name}.rs")),
                dirs.children.join(name).join("mod.rs"),
            ],
        };
        for file in candidates {
            let file = normalise(&file);
            if self.open.contains(&file) {
                return;
            }
            if let Some(src) = (self.read)(&file) {
                let stem = file
                    .file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or(name)
                    .to_string();
                let dir = file.parent().unwrap_or(Path::new("")).to_path_buf();
                let children = if stem == "mod" { dir } else { dir.join(stem) };
                self.file_module(&file, name, Some(m), test, &src, children);
                return;
            }
        }
        let file = self.krate.modules[m].file.display().to_string();
        self.krate
            .problems
            .push(format!("{file}: no file for `mod {name};`"));
    }

    /// Records the paths, single names and `use` declarations in the tokens of one item.
    fn code(&mut self, toks: &[Token], m: ModId, test: bool) {
        let locals = local_bindings(toks);
        let mut i = 0;
        while i < toks.len() {
            let t = &toks[i].tok;
            let prev = i.checked_sub(1).map(|k| &toks[k].tok);
            if t.is('#') {
                let open = i + 1 + usize::from(toks.get(i + 1).is_some_and(|t| t.tok.is('!')));
                if toks.get(open).is_some_and(|t| t.tok.is('[')) {
                    i = matching(toks, open) + 1;
                    continue;
                }
            }
            if t.is_word("use") && prev.is_none_or(|p| p.is(';') || p.is('{') || p.is('}')) {
                let line = toks[i].line;
                i += 1;
                let mut bound = Vec::new();
                use_tree(toks, &mut i, Vec::new(), &mut bound);
                let module = &mut self.krate.modules[m];
                for (name, path) in bound {
                    module.uses.push(Use {
                        name,
                        path,
                        public: false,
                        test,
                        line,
                    });
                }
                continue;
            }
            let Some(word) = t.ident() else {
                i += 1;
                continue;
            };
            let continues = prev.is_some_and(|p| *p == Tok::PathSep || p.is('.') || p.is('$'));
            if continues || (is_keyword(word) && !matches!(word, "crate" | "self" | "super")) {
                i += 1;
                continue;
            }
            let line = toks[i].line;
            let mut path = vec![word.to_string()];
            let mut j = i + 1;
            while j + 1 < toks.len() && toks[j].tok == Tok::PathSep {
                if toks[j + 1].tok.is('<') {
                    j = matching_angle(toks, j + 1) + 1;
                    continue;
                }
                match toks[j + 1].tok.ident() {
                    Some(seg) => path.push(seg.to_string()),
                    None => break,
                }
                j += 2;
            }
            let single = path.len() == 1 && !matches!(word, "crate" | "self" | "super");
            let binds = prev.and_then(Tok::ident).is_some_and(|p| {
                matches!(
                    p,
                    "let"
                        | "mut"
                        | "ref"
                        | "fn"
                        | "struct"
                        | "enum"
                        | "union"
                        | "trait"
                        | "type"
                        | "const"
                        | "static"
                        | "mod"
                        | "as"
                        | "macro_rules"
                )
            });
            // `x: T` (a field, parameter or struct literal field) and `x = ..` (an assignment or
            // a named format argument) name no item.
            let field_or_param = toks.get(j).is_some_and(|t| t.tok.is(':'));
            let assigned = toks.get(j).is_some_and(|t| t.tok.is('='))
                && !toks
                    .get(j + 1)
                    .is_some_and(|t| t.tok.is('=') || t.tok.is('>'));
            let local = locals.contains(word);
            if !(single && (binds || field_or_param || assigned || local)) {
                self.krate.modules[m].refs.push(Ref { path, test, line });
            }
            i = j;
        }
    }
}

/// The lower-case names an item's code binds as locals: in `let` and `for` patterns and closure
/// parameters (`|a, (b, c)|`). A single name among them is a variable, not an item, anywhere in
/// the item (a deliberate simplification: Rust's scopes are narrower).
fn local_bindings(toks: &[Token]) -> BTreeSet<String> {
    let mut locals = BTreeSet::new();
    let lower = |w: &str| w.starts_with(|c: char| c.is_lowercase() || c == '_') && !is_keyword(w);
    let mut i = 0;
    while i < toks.len() {
        let t = &toks[i].tok;
        if t.is_word("let") || t.is_word("for") {
            // The pattern: up to `=`, `:` or `in` outside brackets.
            let mut depth = 0usize;
            let mut j = i + 1;
            while let Some(tok) = toks.get(j).map(|t| &t.tok) {
                if tok.is('(') || tok.is('[') || tok.is('{') {
                    depth += 1;
                } else if tok.is(')') || tok.is(']') || tok.is('}') {
                    if depth == 0 {
                        break;
                    }
                    depth -= 1;
                } else if depth == 0
                    && (tok.is('=') || tok.is(':') || tok.is(';') || tok.is_word("in"))
                {
                    break;
                }
                if let Some(w) = tok.ident() {
                    let next = toks.get(j + 1).map(|t| &t.tok);
                    let pattern_path =
                        next.is_some_and(|n| n.is('(') || n.is('{') || *n == Tok::PathSep);
                    if lower(w) && !pattern_path && toks[j - 1].tok != Tok::PathSep {
                        locals.insert(w.to_string());
                    }
                }
                j += 1;
            }
            i = j;
            continue;
        }
        if t.is('|') {
            // Closure parameters: only names, `mut`, `&`, `_`, commas and parentheses up to the
            // next `|` (a type annotation ends the scan; its names are read by the caller).
            let mut j = i + 1;
            let mut names = Vec::new();
            while let Some(tok) = toks.get(j).map(|t| &t.tok) {
                match tok {
                    Tok::Ident(w) if lower(w) => names.push(w.clone()),
                    Tok::Ident(w) if w == "mut" || w == "_" => {}
                    Tok::Punct(',' | '&' | '(' | ')') => {}
                    _ => break,
                }
                j += 1;
            }
            if toks.get(j).is_some_and(|t| t.tok.is('|') || t.tok.is(':')) {
                locals.extend(names);
            }
        }
        i += 1;
    }
    locals
}

/// Reads one use tree at `pos` (after `use`), appending `(bound name, path)`; a glob binds `None`.
pub fn use_tree(
    toks: &[Token],
    pos: &mut usize,
    prefix: Vec<String>,
    out: &mut Vec<(Option<String>, Vec<String>)>,
) {
    let mut path = prefix;
    if toks.get(*pos).is_some_and(|t| t.tok == Tok::PathSep) {
        // `use ::std::..`: an extern crate.
        path.push("::".to_string());
        *pos += 1;
    }
    while let Some(t) = toks.get(*pos) {
        if t.tok.is('{') {
            *pos += 1;
            while toks.get(*pos).is_some_and(|t| !t.tok.is('}')) {
                use_tree(toks, pos, path.clone(), out);
                if toks.get(*pos).is_some_and(|t| t.tok.is(',')) {
                    *pos += 1;
                }
            }
            *pos += 1;
            return;
        }
        if t.tok.is('*') {
            *pos += 1;
            out.push((None, path));
            return;
        }
        let Some(seg) = t.tok.ident() else {
            // Unexpected: skip the token so the caller's loop always advances.
            *pos += 1;
            return;
        };
        *pos += 1;
        if toks.get(*pos).is_some_and(|t| t.tok == Tok::PathSep) {
            path.push(seg.to_string());
            *pos += 1;
            continue;
        }
        let mut name = if seg == "self" {
            path.last().cloned().unwrap_or_default()
        } else {
            seg.to_string()
        };
        if seg != "self" {
            path.push(seg.to_string());
        }
        if toks.get(*pos).is_some_and(|t| t.tok.is_word("as")) {
            name = toks
                .get(*pos + 1)
                .and_then(|t| t.tok.ident())
                .unwrap_or("_")
                .to_string();
            *pos += 2;
        }
        out.push((Some(name), path));
        return;
    }
}

/// The index just past the item starting at `start`: its `;`, or the `}` that closes its body
/// (unless `semicolon_only`, as for `const X: T = T { .. };`).
fn item_end(toks: &[Token], start: usize, semicolon_only: bool) -> usize {
    let mut depth = 0usize;
    let mut i = start;
    while i < toks.len() {
        let t = &toks[i].tok;
        if t.is('(') || t.is('[') || t.is('{') {
            depth += 1;
        } else if t.is(')') || t.is(']') || t.is('}') {
            if depth == 0 {
                // The enclosing module's `}`: the item ended without one.
                return i;
            }
            depth -= 1;
            if depth == 0 && t.is('}') && !semicolon_only {
                return i + 1;
            }
        } else if t.is(';') && depth == 0 {
            return i + 1;
        }
        i += 1;
    }
    toks.len()
}

/// The index of the bracket that closes the one at `open` (or the end of the tokens).
fn matching(toks: &[Token], open: usize) -> usize {
    let mut depth = 0usize;
    for (i, t) in toks.iter().enumerate().skip(open) {
        if t.tok.is('(') || t.tok.is('[') || t.tok.is('{') {
            depth += 1;
        } else if t.tok.is(')') || t.tok.is(']') || t.tok.is('}') {
            depth -= 1;
            if depth == 0 {
                return i;
            }
        }
    }
    toks.len()
}

/// The index of the `>` that closes the generic arguments opened at `open` (`->` is not one).
fn matching_angle(toks: &[Token], open: usize) -> usize {
    let mut depth = 0usize;
    for (i, t) in toks.iter().enumerate().skip(open) {
        if t.tok.is('<') {
            depth += 1;
        } else if t.tok.is('>') && !(i > 0 && toks[i - 1].tok.is('-')) {
            depth -= 1;
            if depth == 0 {
                return i;
            }
        } else if t.tok.is(';') || t.tok.is('{') {
            return i;
        }
    }
    toks.len()
}

/// Whether an attribute's tokens (inside `#[..]`) are `cfg(test)`.
fn is_cfg_test(attr: &[Token]) -> bool {
    let words: Vec<&Tok> = attr.iter().map(|t| &t.tok).collect();
    matches!(words.as_slice(), [c, open, t, close] if c.is_word("cfg") && open.is('(') && t.is_word("test") && close.is(')'))
}

/// The file of a `#[path = "file"]` attribute.
fn path_attribute(attr: &[Token]) -> Option<String> {
    match attr {
        [p, eq, s] if p.tok.is_word("path") && eq.tok.is('=') => match &s.tok {
            Tok::Str(file) => Some(file.clone()),
            _ => None,
        },
        _ => None,
    }
}

/// `a/./b/../c` -> `a/c` (without touching the file system).
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir if out.file_name().is_some_and(|n| n != "..") => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

/// Rust's keywords and the primitive types: never a module's item.
fn is_keyword(word: &str) -> bool {
    matches!(
        word,
        "as" | "async"
            | "await"
            | "break"
            | "const"
            | "continue"
            | "crate"
            | "dyn"
            | "else"
            | "enum"
            | "extern"
            | "false"
            | "fn"
            | "for"
            | "if"
            | "impl"
            | "in"
            | "let"
            | "loop"
            | "match"
            | "mod"
            | "move"
            | "mut"
            | "pub"
            | "ref"
            | "return"
            | "self"
            | "Self"
            | "static"
            | "struct"
            | "super"
            | "trait"
            | "true"
            | "type"
            | "unsafe"
            | "use"
            | "where"
            | "while"
            | "union"
            | "_"
            | "bool"
            | "char"
            | "str"
            | "u8"
            | "u16"
            | "u32"
            | "u64"
            | "u128"
            | "usize"
            | "i8"
            | "i16"
            | "i32"
            | "i64"
            | "i128"
            | "isize"
            | "f32"
            | "f64"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_one(files: &[(&str, &str)]) -> Crate {
        let files: BTreeMap<PathBuf, String> = files
            .iter()
            .map(|(p, s)| (PathBuf::from(p), s.to_string()))
            .collect();
        read_crate(Path::new("src/lib.rs"), &|p: &Path| files.get(p).cloned())
    }

    fn uses(src: &str) -> Vec<(Option<String>, Vec<String>)> {
        let toks = lex(src);
        let mut pos = 0;
        let mut out = Vec::new();
        use_tree(&toks, &mut pos, Vec::new(), &mut out);
        out
    }

    #[test]
    fn use_trees_bind_names_to_paths() {
        let got = uses("crate::a::{self, b::{C, D as E}, *};");
        let s = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(
            got,
            vec![
                (Some("a".into()), s(&["crate", "a"])),
                (Some("C".into()), s(&["crate", "a", "b", "C"])),
                (Some("E".into()), s(&["crate", "a", "b", "D"])),
                (None, s(&["crate", "a"])),
            ]
        );
    }

    #[test]
    fn modules_files_definitions_and_test_code() {
        let krate = read_one(&[
            ("src/lib.rs", "pub mod a;\nmod b { pub fn inner() {} }\npub struct Top;\n#[cfg(test)]\nmod tests { use super::*; }"),
            ("src/a.rs", "mod deep;\nuse crate::Top;\npub(crate) fn f() -> Top { crate::b::inner(); deep::g(); Top }"),
            ("src/a/deep.rs", "pub fn g() { let x: u8 = 1; }"),
        ]);
        assert!(krate.problems.is_empty(), "{:?}", krate.problems);
        let names: Vec<&str> = krate.modules.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["crate", "a", "deep", "b", "tests"]);
        let a = &krate.modules[1];
        assert_eq!(a.file, PathBuf::from("src/a.rs"));
        assert_eq!(a.defs.get("f"), Some(&true));
        let paths: Vec<String> = a.refs.iter().map(|r| r.path.join("::")).collect();
        assert_eq!(paths, ["Top", "crate::b::inner", "deep::g", "Top"]);
        assert_eq!(krate.modules[2].file, PathBuf::from("src/a/deep.rs"));
        assert!(
            krate.modules[2].refs.is_empty(),
            "a `let` binding and its type are not refs"
        );
        assert!(krate.modules[4].test && !krate.modules[3].test);
        assert_eq!(krate.modules[4].uses[0].path, ["super"]);
    }

    #[test]
    fn a_missing_module_file_is_a_problem_not_a_panic() {
        let krate = read_one(&[("src/lib.rs", "mod gone;")]);
        assert_eq!(krate.problems.len(), 1);
    }
}
