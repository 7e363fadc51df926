#!/usr/bin/env python3
"""Checks every #include of Keel's C++ sources against the layer table of docs/design.md.

    check_layers.py [ROOT]      exit 0 when every include is allowed, 1 naming each that is not

The table sits between `<!-- layers: begin -->` and `<!-- layers: end -->`. Each row names its
folders (backticked; `dir/*` makes each subfolder a unit of its own) and, in "may include",
the folders (or `dir/*/file.h` patterns) its files may include; an item followed by
"(`a.cc`, `b.cc` only)" is allowed to those files of the row alone. A file may always include
its own unit. Only the rows named in PROCESSES may include Boost.Asio or Beast.
"""
import fnmatch
import os
import re
import sys

BEGIN, END = "<!-- layers: begin -->", "<!-- layers: end -->"
PROCESSES = ("client/", "server/", "worker/main/")
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^">]+)[">]')
NETWORK = re.compile(r"^boost/(asio|beast)\b")


class Rule:
    def __init__(self, layer, folders, allowed):
        self.layer = layer
        self.folders = folders  # ["worker/slam/", "worker/stages/*"]
        self.allowed = allowed  # [(pattern, only_files or None)]


def split_items(cell):
    """Splits a table cell at commas outside parentheses."""
    items, depth, current = [], 0, ""
    for ch in cell:
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
        if ch == "," and depth == 0:
            items.append(current.strip())
            current = ""
        else:
            current += ch
    if current.strip():
        items.append(current.strip())
    return items


def read_rules(design_md):
    text = open(design_md, encoding="utf-8").read()
    if BEGIN not in text or END not in text:
        raise SystemExit(f"{design_md}: no layer table between {BEGIN} and {END}")
    rows = [line for line in text.split(BEGIN, 1)[1].split(END, 1)[0].splitlines()
            if line.startswith("|")]
    rules = []
    for line in rows[2:]:  # past the header and its rule
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 3:
            raise SystemExit(f"{design_md}: layer row without three cells: {line}")
        folders = re.findall(r"`([^`]+)`", cells[1])
        allowed = []
        for item in split_items(cells[2]):
            names = re.findall(r"`([^`]+)`", item)
            if not names:
                continue
            only = names[1:] if "only" in item and len(names) > 1 else None
            allowed.append((names[0], only))
        rules.append(Rule(cells[0], folders, allowed))
    return rules


def unit_of(path, rules):
    """(rule, unit folder) of a repository path, or (None, None) when no row holds it."""
    best = (None, None, -1)
    for rule in rules:
        for folder in rule.folders:
            if folder.endswith("/*"):
                base = folder[:-1]
                if path.startswith(base) and "/" in path[len(base):]:
                    unit = base + path[len(base):].split("/", 1)[0] + "/"
                    if len(base) > best[2]:
                        best = (rule, unit, len(base))
            elif path.startswith(folder) and len(folder) > best[2]:
                best = (rule, folder, len(folder))
    return best[0], best[1]


def matches(target, pattern):
    if pattern.endswith("/*"):
        return target.startswith(pattern[:-1])
    if "*" in pattern:
        return fnmatch.fnmatchcase(target, pattern)
    return target.startswith(pattern) if pattern.endswith("/") else target == pattern


def check(root):
    rules = read_rules(os.path.join(root, "docs", "design.md"))
    problems = []
    for rule in rules:
        for folder in rule.folders:
            base = os.path.join(root, folder.rstrip("*").rstrip("/"))
            for directory, _, files in os.walk(base):
                for name in sorted(files):
                    if name.endswith((".cc", ".h")):
                        problems += check_file(root, os.path.join(directory, name), rules)
    return sorted(set(problems))


def check_file(root, file_path, rules):
    path = os.path.relpath(file_path, root).replace(os.sep, "/")
    rule, unit = unit_of(path, rules)
    if rule is None:
        return []
    problems = []
    with open(file_path, encoding="utf-8", errors="replace") as source:
        for number, line in enumerate(source, 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            kind, target = m.groups()
            where = f"{path}:{number}"
            if kind == "<" or not os.path.isfile(os.path.join(root, target)):
                if NETWORK.match(target) and not path.startswith(PROCESSES):
                    problems.append(f"{where}: includes <{target}>, but only the processes "
                                    f"({', '.join(PROCESSES)}) may use Boost.Asio or Beast")
                continue
            if target.startswith(unit):
                continue
            ok = any(matches(target, pattern) and (only is None or os.path.basename(path) in only)
                     for pattern, only in rule.allowed)
            if not ok:
                target_rule, _ = unit_of(target, rules)
                layer = target_rule.layer if target_rule else "no layer"
                problems.append(f'{where}: includes "{target}" ({layer}), which the layer '
                                f"'{rule.layer}' may not use (docs/design.md, Layers)")
    return problems


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(__file__), ".."))
    problems = check(root)
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} include(s) break the layer table of docs/design.md")
        return 1
    print("every include follows the layer table of docs/design.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
