#!/usr/bin/env python3
"""The design pages against the tree: docs/design/architecture.md and docs/design/layers.md name
every source file and folder, and nothing that is not there. The lint stage runs it.

  scripts/ci/design_pages.py [--root DIR]

The tree is `git ls-files --cached --others --exclude-standard` (a new file counts before it is
added), less what the work tree has lost. Only inline code spans (`...`) name things; fenced
blocks and links do not (test/docs/test_docs.py checks the links).

What must be named:
  files    every file under src/, include/, scripts/, bench/, msg/, srv/, launch/, urdf/, config/
  folders  every folder holding those files, every folder directly under test/, and every
           top-level folder but the hidden ones, build/, output/ and docs/
A named path names the folders it lies in too (`src/core/session/` names src/core/ and src/).
A header names itself, or is named with its source: position.h is named when position.c beside it
is, so a module is one entry, not two; a header with no source of its name (data.h) is named
itself.

How a span names a path. A span's context is the folders named in its table row, list item or
paragraph, plus those in its table's header row and its heading. A span is read
  1. relative to each context folder (`position.c` in the physics row is
     src/core/physics/position.c; `session/` in a row whose page names `src/core/` elsewhere is
     src/core/session/, see below),
  2. else from the repository's root (`src/core/check_layers.cmake`, `test/ros/`; a word with no
     '/' only as a file: `bench` in a row about scripts/ is not the folder bench/),
  3. else, for a bare file name in a block that names no folder at all, as the one file of that
     name in the tree (`rest.yaml` in a sentence); a name two files share must say which.
A span with a '/' that is none of these is read relative to the folders the two pages name from
the root, when exactly one fits (`session/` is src/core/session/ because the pages name src/core/).
Step 3 is not taken when the block has folders: there a file must be where the block says, so a
file that moves to another layer or folder makes its old row stale, and the message says where
the file is now.

Why this rule: a row names its folder once and its files by name, as a reader reads it, so no file
is spelt out in full and no header is listed twice (once as a module's .h, once as its .c; once in
include/flex3rpr/, once in its layer's row: the layer table's header row says `include/flex3rpr/`).
Yet every file needs a mention of its own where it lives: a new file, a moved one or a deleted one
fails, and so does a new folder under test/ or at the top.

Which spans must exist: a span is a path when it contains '/' or ends in a source extension
(.c .h .cpp .hpp .py .def .msg .srv .launch .yaml .urdf .cmake .md .txt .R .rviz .sh); a span with
spaces (a command) is split and each such word checked (`scripts/ci/file_graph --check`); words
under build/ or output/ are what a build makes and are passed over. In a block about a folder of
commands (one holding a file with no extension, like scripts/ and bench/), a bare word is a
command and must exist there too (`sweep`). These are not paths: names starting with '~' or '/'
(topics, parameters, ROS names), '-' (options), f3r_ without a source extension (C functions and
types; `f3r_peer.c` is a file), and spans with any
of ( ) = : % < > * $ (calls, settings, formats, globs) or a dot but no source extension
(`solver.rtol`).

Prints one line per problem and exits 1, or prints `design pages: N files and M folders named,
nothing stale` and exits 0. check(pages, files) returns the problems for page files and a list of
repository-relative file names, for a test to call."""
import argparse
import os
import posixpath
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
PAGES = ("docs/design/architecture.md", "docs/design/layers.md")
SOURCE_TREES = ("src", "include", "scripts", "bench", "msg", "srv", "launch", "urdf", "config")
NOT_SOURCE_TOP = ("build", "output", "docs")
GENERATED = ("build", "output")  # what a build or a run makes: `cmake -B build/core` names no file
EXTENSIONS = {".c", ".h", ".cpp", ".hpp", ".py", ".def", ".msg", ".srv", ".launch", ".yaml", ".urdf",
              ".cmake", ".md", ".txt", ".R", ".rviz", ".sh"}
HEADER_SOURCE = {".h": ".c", ".hpp": ".cpp"}
NOT_PATH_CHARS = set("()=:%<>*$")
BARE_WORD = re.compile(r"^[A-Za-z0-9_.][A-Za-z0-9_.+-]*$")
SPAN = re.compile(r"(`+)(.+?)\1")
TABLE_SEPARATOR = re.compile(r"^\|?\s*:?-+:?\s*(\|\s*:?-+:?\s*)*\|?\s*$")
LIST_ITEM = re.compile(r"^\s*([-*+]|\d+[.)])\s")


def tree_files(root):
    """The repository's files, relative to root: tracked, and new ones git does not ignore."""
    out = subprocess.run(["git", "-C", root, "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                         capture_output=True, check=True)
    files = [f for f in out.stdout.decode().split("\0") if f]
    # a file git tracks but the work tree lost (deleted or moved, not yet committed) is not there
    return [f for f in files if os.path.isfile(os.path.join(root, f))]


def blocks(text):
    """The page's blocks as (line, text, inherited): a table row, list item, paragraph or heading,
    and the text its context comes from besides its own (its table's header row, its heading)."""
    out, current, heading, header, fence = [], None, "", None, None
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        marker = re.match(r"^(```|~~~)", stripped)
        if fence or marker:  # a fenced block: code, not names
            if marker and (fence is None or stripped.startswith(fence)):
                fence = None if fence else marker.group(1)
            current = None
            continue
        if not stripped:
            current, header = None, None
        elif stripped.startswith("#"):
            heading = stripped
            out.append([number, stripped, ""])
            current = None
        elif stripped.startswith("|"):
            if TABLE_SEPARATOR.match(stripped):
                continue
            if header is None:  # the first row of a table is its header
                header = stripped
                out.append([number, stripped, heading])
            else:
                out.append([number, stripped, heading + "\n" + header])
            current = None
        elif LIST_ITEM.match(line) or current is None:
            current, header = [number, stripped, heading], None
            out.append(current)
        else:  # a paragraph's or list item's next line
            current[1] += "\n" + stripped
    return [tuple(b) for b in out]


def spans(text):
    return [m.group(2).strip() for m in SPAN.finditer(text)]


def is_name(word):
    """A ROS name, option, C identifier, call, setting or format: not a path."""
    if word[0] in "~/-" or NOT_PATH_CHARS & set(word):
        return True
    return word.startswith("f3r_") and not looks_like_path(word)  # f3r_microbench.c is a file


def candidates(span):
    """The words of a span that may be paths: (word, must_be_path)."""
    if " " in span or "\t" in span or "\n" in span:
        words = [w for w in span.split() if not is_name(w) and looks_like_path(w)]
        return [(w, True) for w in words if w.split("/")[0] not in GENERATED]
    if is_name(span) or not BARE_WORD.match(span.rstrip("/").replace("/", "_")):
        return []
    return [(span, looks_like_path(span))]


def looks_like_path(word):
    return "/" in word or os.path.splitext(word)[1] in EXTENSIONS


class Tree:
    def __init__(self, files):
        self.files = set(files)
        self.dirs = {posixpath.dirname(f) for f in self.files}
        for d in list(self.dirs):
            while d:
                self.dirs.add(d)
                d = posixpath.dirname(d)
        self.dirs.discard("")
        self.by_name = {}
        for f in self.files:
            self.by_name.setdefault(posixpath.basename(f), []).append(f)
        # folders of commands: a file without an extension lies directly in them
        self.command_dirs = {posixpath.dirname(f) for f in self.files
                             if "." not in posixpath.basename(f) and posixpath.dirname(f)}

    def exists(self, path):
        return path in self.files or path in self.dirs

    def is_dir(self, path):
        return path in self.dirs


def clean(word):
    return posixpath.normpath(word.rstrip("/")) if word.rstrip("/") else word


def relative(base, word):
    return clean(posixpath.join(base, word))


class Page:
    """A page's blocks, each with its words and the folders that are its context."""

    def __init__(self, path, label):
        self.path, self.label = path, label
        try:
            with open(path, encoding="utf-8") as f:
                self.blocks, self.missing = blocks(f.read()), False
        except FileNotFoundError:
            self.blocks, self.missing = [], True


def block_folders(text, tree, root_folders):
    """The folders a piece of text names: from the root, relative to each other, or relative to
    root_folders when exactly one fits."""
    words = [clean(w) for s in spans(text) for w, _ in candidates(s) if "/" in w]  # `bench` is a word
    found = [w for w in words if tree.is_dir(w)]
    for w in words:
        if w in found:
            continue
        near = sorted({relative(d, w) for d in found if tree.is_dir(relative(d, w))})
        far = sorted({relative(d, w) for d in root_folders if tree.is_dir(relative(d, w))})
        found += near or (far if len(far) == 1 else [])
    return found


def read_pages(pages, files):
    """(tree, named paths, problems) for the page files and the repository-relative files."""
    tree = Tree(files)
    pages = [Page(p, label(p)) for p in pages]
    root_folders = sorted({clean(w) for p in pages for _, text, _ in p.blocks for s in spans(text)
                           for w, _ in candidates(s) if "/" in w and tree.is_dir(clean(w))})
    named = set()
    problems = [f"{page.label}: the page is missing" for page in pages if page.missing]
    for page in pages:
        for _, text, inherited in page.blocks:
            context = block_folders(inherited + "\n" + text, tree, root_folders)
            for span in spans(text):
                for word, must in candidates(span):
                    hit, problem = resolve(word, must, context, tree, root_folders)
                    named.update(hit)
                    if problem:
                        problems.append(f"{page.label}: names {problem}")
    for path in list(named):
        while path:
            named.add(path)
            path = posixpath.dirname(path)
    return tree, named, problems


def resolve(word, must, context, tree, root_folders):
    """The paths word names, and what is wrong when it names none that it must."""
    path = clean(word)
    near = sorted({relative(d, path) for d in context if tree.exists(relative(d, path))})
    if near:
        return near, None
    if path in tree.files or ("/" in word and tree.is_dir(path)):  # a folder is written with a '/'
        return [path], None
    elsewhere = sorted(tree.by_name.get(posixpath.basename(path), []))
    if "/" not in path and not context and len(elsewhere) == 1:
        return elsewhere, None
    if "/" in word:
        far = sorted({relative(d, path) for d in root_folders if tree.exists(relative(d, path))})
        if len(far) == 1:
            return far, None
    commands = [d for d in context if d in tree.command_dirs]
    if not must and not commands:
        return [], None  # a bare word outside a folder of commands: a name, not a path
    where = context if must else commands
    text = f"{word}, which does not exist"
    if where and "/" not in path:
        text += " in " + " or ".join(d + "/" for d in where)
    if elsewhere:
        text += " (the tree has " + ", ".join(elsewhere) + ")"
    elif not must:
        text += " (a bare word in a block about a folder of commands is read as a command there)"
    return [], text


def required(tree):
    """The source files and folders the pages must name."""
    files = {f for f in tree.files if f.split("/")[0] in SOURCE_TREES}
    dirs = {d for d in tree.dirs if d.split("/")[0] in SOURCE_TREES}
    dirs |= {d for d in tree.dirs if d.startswith("test/") and d.count("/") == 1}
    dirs |= {d for d in tree.dirs if "/" not in d and not d.startswith(".") and d not in NOT_SOURCE_TOP}
    return files, dirs


def label(path):
    full = os.path.abspath(path)
    if full.startswith(ROOT + os.sep):
        return os.path.relpath(full, ROOT).replace(os.sep, "/")
    return path


def unnamed(tree, named, pages):
    files, dirs = required(tree)
    missing = []
    for f in sorted(files):
        stem, ext = posixpath.splitext(f)
        if f in named or (ext in HEADER_SOURCE and stem + HEADER_SOURCE[ext] in named):
            continue
        missing.append(f)
    missing += [d + "/" for d in sorted(dirs) if d not in named]
    names = [label(p) for p in pages]
    where = "neither " + " nor ".join(names) if len(names) == 2 else "none of " + ", ".join(names)
    return [f"{m} is named in {where}" for m in missing]


def check(pages, files):
    """The problems, one line each: page names that do not exist, then source files and folders
    that no page names. pages: paths of the page files; files: the tree, repository-relative."""
    tree, named, problems = read_pages(pages, files)
    return problems + unnamed(tree, named, pages)


def main():
    global ROOT
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", default=ROOT, help="the checkout to check (default: this one)")
    args = ap.parse_args()
    ROOT = os.path.realpath(args.root)
    pages = [os.path.join(ROOT, p) for p in PAGES]
    files = tree_files(ROOT)
    problems = check(pages, files)
    for p in problems:
        print(p)
    if problems:
        return 1
    tree, named, _ = read_pages(pages, files)
    print(f"design pages: {len(named & tree.files)} files and {len(named & tree.dirs)} folders named, "
          "nothing stale")
    return 0


if __name__ == "__main__":
    sys.exit(main())
