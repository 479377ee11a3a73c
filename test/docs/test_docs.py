#!/usr/bin/env python3
"""The documents' own checks: nothing they point at is missing, nothing the scene loader accepts
is left out of docs/scenes.md, and the README stays a five-minute read.

usage: test_docs.py [--junit FILE] [--root DIR]

  a  every relative link and image in every tracked *.md file resolves to a file or folder of
     the repository (anchors into Markdown files are checked against their headings)
  b  every field the scene loader accepts (src/core/scene/scene_yaml.c, the input names of
     src/core/scene/scene.c) appears in docs/scenes.md
  c  README.md has at most 200 lines, opens with the two set-up commands, and its count of
     invalid scenes is the corpus's
  d  no tracked file cites a path outside the repository (the shared folder beside it, its
     model notes)
  e  every patch kept as an experiment (*.patch) names the commit it is pinned to on its first
     line ("Pinned: COMMIT") and applies there (git apply --check on that commit's files)

Exit 0 when all pass, 1 otherwise; --junit FILE writes JUnit XML as the other Python suites do.
Needs only python3 and git (without git, every *.md outside build/ and .git/ is checked).
"""

import argparse
import os
import re
import subprocess
import sys
import unittest
import xml.etree.ElementTree as ET

# realpath: the catkin workspace links the checkout's folders one by one under build/, which git ignores
ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
README_MAX_LINES = 200
README_COMMANDS = ["bash scripts/demo", "bash scripts/test"]
MIN_SCENE_KEYS = 30
# Paths outside the repository that files once cited, spelt in pieces so that this file does not
# cite them itself (a grep over the repository must find nothing).
OUTSIDE = ("../" + "shared", "MODEL" + ".md")


def tracked_files():
    """The repository's files, relative to ROOT: tracked, and new ones git does not ignore."""
    try:
        out = subprocess.run(["git", "-C", ROOT, "ls-files", "-z", "--cached", "--others",
                              "--exclude-standard"], capture_output=True, check=True)
        files = [f for f in out.stdout.decode().split("\0") if f]
        # a file git tracks but the work tree lost (deleted, not yet committed) is not there
        return [f for f in files if os.path.exists(os.path.join(ROOT, f))]
    except (OSError, subprocess.CalledProcessError):
        files = []
        for top, dirs, names in os.walk(ROOT):
            dirs[:] = [d for d in dirs if d not in (".git", "build", "output")]
            files += [os.path.relpath(os.path.join(top, n), ROOT) for n in names]
        return files


def markdown_files():
    return sorted(f for f in tracked_files() if f.endswith(".md"))


def strip_code(text, inline=True):
    """Markdown without its fenced blocks and (inline) its code spans, line count kept."""
    out, fence = [], None
    for line in text.split("\n"):
        m = re.match(r"^\s*(```+|~~~+)", line)
        if fence:
            if m and m.group(1)[0] == fence[0] and len(m.group(1)) >= len(fence):
                fence = None
            out.append("")
            continue
        if m:
            fence = m.group(1)
            out.append("")
            continue
        out.append(re.sub(r"(`+)(?:(?!\1).)+?\1", "", line) if inline else line)
    return "\n".join(out)


LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+.*)?$", re.M)
HTML_SRC = re.compile(r"<(?:img|a)\s[^>]*(?:src|href)=\"([^\"]+)\"", re.I)


def links(text):
    """(line number, target) of every inline link, image, reference definition and HTML src."""
    body = strip_code(text)
    found = []
    for pattern in (LINK, REFERENCE, HTML_SRC):
        for m in pattern.finditer(body):
            found.append((body.count("\n", 0, m.start()) + 1, m.group(1)))
    return found


def anchors(markdown_text):
    """The heading anchors a repository host generates (GitHub's rule: lower case, punctuation
    dropped, spaces to hyphens, repeats numbered)."""
    seen, result = {}, set()
    for line in strip_code(markdown_text, inline=False).split("\n"):
        m = re.match(r"^\s{0,3}#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        slug = re.sub(r"[^\w\- ]", "", m.group(1).lower().replace("`", "")).replace(" ", "-")
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        result.add(slug if n == 0 else "%s-%d" % (slug, n))
    for m in re.finditer(r"<a\s+(?:name|id)=\"([^\"]+)\"", markdown_text):
        result.add(m.group(1))
    return result


def is_external(target):
    return re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target) is not None or target.startswith("//")


def scene_keys():
    """Every key the scene loader compares a YAML key with, and the input names."""
    src = open(os.path.join(ROOT, "src", "core", "scene", "scene_yaml.c")).read()
    keys = set()
    # strcmp(key, "x"), strcmp(ekey, "x"), ... : a mapping key (not strcmp(v, ...): a value)
    keys.update(re.findall(r"strcmp\(\s*\w*key\s*,\s*\"([a-z_0-9]+)\"\s*\)", src))
    # the number tables: F3R_NUMBER("x", ...), F3R_INTEGER("x", ...), F3R_VECTOR("x", ...)
    keys.update(re.findall(r"F3R_(?:NUMBER|INTEGER|VECTOR)\(\s*\"([a-z_0-9]+)\"", src))
    # the top-level sections: {"geometry", read_geometry}, ...
    keys.update(re.findall(r"\{\s*\"([a-z_0-9]+)\"\s*,\s*read_\w+\s*\}", src))
    scene_c = open(os.path.join(ROOT, "src", "core", "scene", "scene.c")).read()
    names = re.search(r"kInputNames\s*\[[^\]]*\]\s*=\s*\{([^}]*)\}", scene_c)
    inputs = set(re.findall(r"\"([a-z_0-9]+)\"", names.group(1))) if names else set()
    return keys, inputs


class Links(unittest.TestCase):
    def test_a_every_relative_link_resolves(self):
        files = markdown_files()
        self.assertGreater(len(files), 10, "found the repository's Markdown files")
        bad, count = [], 0
        for md in files:
            text = open(os.path.join(ROOT, md), encoding="utf-8").read()
            for line, target in links(text):
                if is_external(target) or target.startswith("#") and not target[1:]:
                    continue
                count += 1
                path, _, anchor = target.partition("#")
                if not path:  # an anchor into this file
                    resolved = os.path.join(ROOT, md)
                else:
                    resolved = os.path.normpath(os.path.join(ROOT, os.path.dirname(md), path))
                    if os.path.relpath(resolved, ROOT).startswith(".."):
                        bad.append("%s:%d: %s leaves the repository" % (md, line, target))
                        continue
                    if not os.path.exists(resolved):
                        bad.append("%s:%d: %s: no such file" % (md, line, target))
                        continue
                if anchor and resolved.endswith(".md") and os.path.isfile(resolved):
                    if anchor not in anchors(open(resolved, encoding="utf-8").read()):
                        bad.append("%s:%d: %s: no heading with anchor #%s" % (md, line, target, anchor))
        self.assertGreater(count, 20, "found the documents' relative links")
        self.assertEqual(bad, [], "\n" + "\n".join(bad))

    def test_d_nothing_cites_a_path_outside_the_repository(self):
        bad = []
        for f in tracked_files():
            p = os.path.join(ROOT, f)
            if not os.path.isfile(p):
                continue
            try:
                text = open(p, encoding="utf-8").read()
            except (UnicodeDecodeError, OSError):
                continue
            for n, line in enumerate(text.split("\n"), 1):
                if any(p in line for p in OUTSIDE):
                    bad.append("%s:%d: %s" % (f, n, line.strip()[:120]))
        self.assertEqual(bad, [], "\n" + "\n".join(bad))


class Scenes(unittest.TestCase):
    def test_b_every_scene_field_is_documented(self):
        keys, inputs = scene_keys()
        self.assertGreaterEqual(len(keys), MIN_SCENE_KEYS,
                                "scene_yaml.c: found only %d keys %s: has the loader changed its "
                                "form? Update scene_keys()" % (len(keys), sorted(keys)))
        self.assertEqual(len(inputs), 9, "scene.c: the nine input names, found %s" % sorted(inputs))
        for expected in ("geometry", "stroke_max", "modes", "static_correction", "exact_kinematics",
                         "time_constant", "max_order", "end_effector", "interpolation", "chirp"):
            self.assertIn(expected, keys, "scene_keys() misses a key it must find")
        doc = open(os.path.join(ROOT, "docs", "scenes.md"), encoding="utf-8").read()
        words = set(re.findall(r"[A-Za-z_0-9]+", doc))
        missing = sorted(k for k in keys | inputs if k not in words)
        self.assertEqual(missing, [], "docs/scenes.md does not name: %s" % ", ".join(missing))


class Patches(unittest.TestCase):
    def test_e_every_patch_applies_to_its_pinned_commit(self):
        import shutil
        import tempfile
        patches = [f for f in tracked_files() if f.endswith(".patch")]
        self.assertTrue(patches, "no patches found: the check would pass on nothing")
        for name in patches:
            path = os.path.join(ROOT, name)
            with open(path, encoding="utf-8") as f:
                first = f.readline().split()
            self.assertEqual(len(first), 2, "%s: the first line is 'Pinned: COMMIT'" % name)
            self.assertEqual(first[0], "Pinned:", "%s: the first line is 'Pinned: COMMIT'" % name)
            known = subprocess.run(["git", "-C", ROOT, "cat-file", "-e", first[1] + "^{commit}"],
                                   capture_output=True)
            if known.returncode != 0:  # a shallow clone: say so, do not pass
                self.skipTest("%s: commit %s is not in this clone (shallow?)" % (name, first[1]))
            files = re.findall(r"^--- a/(\S+)$", open(path, encoding="utf-8").read(), re.M)
            tmp = tempfile.mkdtemp()
            try:
                for f in files:
                    text = subprocess.run(["git", "-C", ROOT, "show", "%s:%s" % (first[1], f)],
                                          capture_output=True, check=True).stdout
                    os.makedirs(os.path.dirname(os.path.join(tmp, f)), exist_ok=True)
                    with open(os.path.join(tmp, f), "wb") as out:
                        out.write(text)
                applied = subprocess.run(["git", "apply", "--check", path], cwd=tmp,
                                         capture_output=True, text=True)
                self.assertEqual(applied.returncode, 0, "%s at %s: %s" % (name, first[1],
                                                                          applied.stderr))
            finally:
                shutil.rmtree(tmp)


class Readme(unittest.TestCase):
    def setUp(self):
        self.lines = open(os.path.join(ROOT, "README.md"), encoding="utf-8").read().split("\n")
        if self.lines and self.lines[-1] == "":
            self.lines.pop()

    def test_c1_at_most_200_lines(self):
        self.assertLessEqual(len(self.lines), README_MAX_LINES, "README.md: %d lines" % len(self.lines))

    def test_c2_opens_with_the_two_commands(self):
        first = next((i for i, line in enumerate(self.lines) if line.startswith("```")), None)
        self.assertIsNotNone(first, "README.md: no code block")
        before = [line for line in self.lines[:first] if line.strip()]
        self.assertTrue(all(line.startswith("# ") for line in before),
                        "README.md: only the title before the first code block, found %s" % before)
        end = next(i for i in range(first + 1, len(self.lines)) if self.lines[i].startswith("```"))
        block = [line for line in self.lines[first + 1:end] if line.strip()]
        self.assertEqual([line.split("#")[0].strip() for line in block], README_COMMANDS,
                         "README.md: the first code block is the two set-up commands")


    def test_c3_the_invalid_scene_count_is_the_corpus(self):
        corpus = [f for f in os.listdir(os.path.join(ROOT, "test", "invalid_scenes"))
                  if f.endswith(".yaml")]
        said = re.findall(r"(\d+) invalid ones", " ".join(self.lines))
        self.assertEqual(said, [str(len(corpus))], "README.md: the invalid scenes' count")


def suite_tests(suite):
    for t in suite:
        if isinstance(t, unittest.TestSuite):
            yield from suite_tests(t)
        else:
            yield t


def run_junit(classes, junit_path, suite_name):
    """Runs the cases, prints unittest's report, writes JUnit XML; exit code 0 when all pass."""
    loader = unittest.TestLoader()
    suite = unittest.TestSuite(loader.loadTestsFromTestCase(c) for c in classes)
    ids = [t.id() for t in suite_tests(suite)]
    result = unittest.TextTestRunner(verbosity=2, stream=sys.stdout).run(suite)
    if junit_path:
        root = ET.Element("testsuite", name=suite_name, tests=str(result.testsRun),
                          failures=str(len(result.failures)), errors=str(len(result.errors)))
        bad = {t.id(): text for t, text in result.failures + result.errors}
        skips = {t.id(): reason for t, reason in result.skipped}
        for test_id in ids:
            parts = test_id.split(".")
            case = ET.SubElement(root, "testcase", classname="%s.%s" % (suite_name, parts[-2]),
                                 name=parts[-1])
            if test_id in bad:
                ET.SubElement(case, "failure", message=bad[test_id][-4000:])
            elif test_id in skips:
                ET.SubElement(case, "skipped", message=skips[test_id])
        for test_id, text in bad.items():
            if test_id not in ids:
                case = ET.SubElement(root, "testcase", classname=suite_name, name=test_id.split(" ")[0])
                ET.SubElement(case, "failure", message=text[-4000:])
        os.makedirs(os.path.dirname(os.path.abspath(junit_path)), exist_ok=True)
        ET.ElementTree(root).write(junit_path)
    return 0 if result.wasSuccessful() else 1


def main():
    global ROOT
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--junit", help="write JUnit XML results here")
    ap.add_argument("--root", help="the repository (default: two folders up from this file)")
    args = ap.parse_args()
    if args.root:
        ROOT = os.path.abspath(args.root)
    return run_junit([Links, Scenes, Readme, Patches], args.junit, "docs")


if __name__ == "__main__":
    sys.exit(main())
