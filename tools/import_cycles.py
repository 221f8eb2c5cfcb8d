#!/usr/bin/env python3
"""Import cycles between the files of a Rust crate.

Usage: tools/import_cycles.py crates/bisph-core/src [more src folders]

Builds the file-level graph of each crate and prints its strongly connected components of more
than one file (exit status 1 when there is one). An edge a -> b when file a names an item of
module b: a `use` of `crate::`, `super::`, `self::` or a child module's path, or such a path
written inline in code (comments, strings and the `#[cfg(test)]` part of a file are left out).
`mod x;` declarations are not edges. A path resolves to the longest module prefix that is a
file (`x.rs` or `x/mod.rs`)."""
import os, re, sys

def strip(src):
    src = re.sub(r'/\*.*?\*/', '', src, flags=re.S)
    src = re.sub(r'//[^\n]*', '', src)
    src = re.sub(r'"(?:\\.|[^"\\])*"', '""', src)
    return src

def module_of(root, path):
    rel = os.path.relpath(path, root)[:-3].split(os.sep)
    if rel[-1] in ('mod', 'lib', 'main'):
        rel = rel[:-1]
    return tuple(rel)

def main(root):
    files = {}
    for d, _, fs in os.walk(root):
        for f in fs:
            if f.endswith('.rs'):
                p = os.path.join(d, f)
                files[module_of(root, p)] = p
    def resolve(mod):
        for k in range(len(mod), -1, -1):
            if mod[:k] in files:
                return mod[:k]
        return None
    edges = {m: set() for m in files}
    path_re = re.compile(r'\b(crate|super|self)((?:::\w+)+)')
    use_re = re.compile(r'\buse\s+([^;]+);')
    for m, p in files.items():
        src = strip(open(p).read())
        # Drop #[cfg(test)] mod tests { ... } bodies: tests may use what they like.
        i = src.find('#[cfg(test)]')
        if i >= 0:
            src = src[:i]
        is_mod_file = p.endswith(('mod.rs', 'lib.rs', 'main.rs'))
        base = m if is_mod_file else m[:-1]   # the module `self` refers to in this file is m
        targets = []
        # Expand `use a::{b, c::{d}}` groups into paths.
        def expand(prefix, body):
            body = body.strip()
            if body.startswith('{') and body.endswith('}'):
                depth, cur, parts = 0, '', []
                for ch in body[1:-1]:
                    if ch == '{': depth += 1
                    if ch == '}': depth -= 1
                    if ch == ',' and depth == 0:
                        parts.append(cur); cur = ''
                    else:
                        cur += ch
                parts.append(cur)
                out = []
                for part in parts:
                    if part.strip():
                        out += expand(prefix, part)
                return out
            j = body.find('::{')
            if j >= 0:
                return expand(prefix + body[:j].split('::'), body[j+2:])
            body = body.split(' as ')[0].strip()
            return [prefix + [s.strip() for s in body.split('::') if s.strip()]]
        uses = []
        for u in use_re.findall(src):
            uses += expand([], u.replace('\n', ' ').replace('pub ', ''))
        for s in path_re.finditer(src):
            uses.append([s.group(1)] + s.group(2).split('::')[1:])
        for segs in uses:
            if not segs:
                continue
            if segs[0] not in ('crate', 'super', 'self'):
                # A path relative to this module (a child module's item), if one exists.
                if resolve(tuple(list(m) + segs[:1])) == tuple(list(m) + segs[:1]):
                    segs = ['self'] + segs
                else:
                    continue
            if segs[0] == 'crate':
                cur = []
                rest = segs[1:]
            else:
                cur = list(m)
                rest = segs
                while rest and rest[0] in ('super', 'self'):
                    if rest[0] == 'super':
                        cur = cur[:-1]
                    rest = rest[1:]
            t = resolve(tuple(cur + [r for r in rest if r != 'self']))
            if t is not None and t != m:
                edges[m].add(t)
    # Tarjan's strongly connected components.
    index, low, stack, on, sccs, n = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(10000)
    def visit(v):
        index[v] = low[v] = n[0]; n[0] += 1; stack.append(v); on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w); low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop(); on.discard(w); comp.append(w)
                if w == v: break
            sccs.append(comp)
    for v in files:
        if v not in index:
            visit(v)
    name = lambda m: os.path.relpath(files[m], root)
    cyclic = [c for c in sccs if len(c) > 1]
    print(f"{root}: {len(files)} files, {sum(len(e) for e in edges.values())} edges, {len(cyclic)} cycles")
    for c in cyclic:
        print("cycle:", ", ".join(sorted(name(m) for m in c)))
        for a in c:
            for b in sorted(edges[a]):
                if b in c:
                    print(f"    {name(a)} -> {name(b)}")
    return 1 if cyclic else 0

if __name__ == '__main__':
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    sys.exit(max(main(root) for root in sys.argv[1:]))
