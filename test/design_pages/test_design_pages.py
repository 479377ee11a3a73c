#!/usr/bin/python3
"""scripts/ci/design_pages.py can fail: copies of docs/design/architecture.md and layers.md,
checked against this checkout's files (as the lint stage lists them), each changed one way:

  - a row names a file that does not exist                   -> "names ..., which does not exist"
  - a file joins the tree that no page names                 -> "... is named in neither ..."
  - a file's only mention is cut from the page               -> "... is named in neither ..."
  - a file moves to another layer's folder                   -> its old row is stale, and the
                                                                file at its new place unnamed
  - topic, parameter, function and field names are added     -> nothing (they are not paths)

Each case compares with the unchanged copies' own problems, so it holds whatever the tree's
state (another change under way may leave the real pages stale for a while).

usage: test_design_pages.py [--junit FILE]     (python3 and git only)"""
import argparse
import os
import shutil
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts", "ci"))
sys.path.insert(0, os.path.join(ROOT, "nodes"))  # the tools' shared module: JUnit XML
import design_pages  # noqa: E402


class DesignPages(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.files = design_pages.tree_files(ROOT)
        cls.original = {}
        for page in design_pages.PAGES:
            with open(os.path.join(ROOT, page), encoding="utf-8") as f:
                cls.original[os.path.basename(page)] = f.read()

    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="design_pages_")
        self.addCleanup(shutil.rmtree, self.dir)
        self.pages = {}
        for name, text in self.original.items():
            self.pages[name] = os.path.join(self.dir, name)
            self.write(name, text)
        self.baseline = set(self.check())

    def write(self, name, text):
        with open(os.path.join(self.dir, name), "w", encoding="utf-8") as f:
            f.write(text)

    def check(self, files=None):
        return design_pages.check(list(self.pages.values()), self.files if files is None else files)

    def new_problems(self, files=None):
        return sorted(set(self.check(files)) - self.baseline)

    def test_a_file_that_does_not_exist(self):
        self.write("architecture.md", self.original["architecture.md"].rstrip("\n") +
                   "\n| `src/core/solve/stepper_nowhere.c` | a stepper never written |\n")
        self.assertEqual(self.new_problems(), [
            self.pages["architecture.md"] + ": names src/core/solve/stepper_nowhere.c, which does not exist"])

    def test_a_bare_name_that_does_not_exist_in_its_row(self):
        text = self.original["architecture.md"]
        row = next(line for line in text.splitlines() if line.startswith("| `src/cli/`"))
        self.write("architecture.md", text.replace(row, row[:-1] + "and `cli_nowhere.c` |"))
        self.assertEqual(self.new_problems(), [
            self.pages["architecture.md"] + ": names cli_nowhere.c, which does not exist in src/cli/"])

    def test_a_new_file_no_page_names(self):
        problems = self.new_problems(self.files + ["src/core/physics/new_stage.c"])
        self.assertEqual(problems, ["src/core/physics/new_stage.c is named in neither " +
                                    self.pages["architecture.md"] + " nor " + self.pages["layers.md"]])

    def test_a_new_folder_no_page_names(self):
        problems = self.new_problems(self.files + ["test/new_suite/test_new.py", "new_top/README.md"])
        self.assertIn("test/new_suite/ is named in neither " + self.pages["architecture.md"] + " nor " +
                      self.pages["layers.md"], problems)
        self.assertIn("new_top/ is named in neither " + self.pages["architecture.md"] + " nor " +
                      self.pages["layers.md"], problems)

    def a_file_named_once(self):
        """A C file of the core that the pages name once, by its bare name, in layers.md."""
        for f in sorted(self.files):
            name = os.path.basename(f)
            if not (f.startswith("src/core/") and f.endswith(".c")):
                continue
            spans = [t.count(f"`{name}`") + t.count(f) for t in self.original.values()]
            if spans == [0, 1] and self.original["layers.md"].count(name) == 1:
                return f
        self.skipTest("no file of the core is named exactly once in layers.md")

    def test_a_file_cut_from_the_page(self):
        path = self.a_file_named_once()
        name = os.path.basename(path)
        self.write("layers.md", self.original["layers.md"].replace(f"`{name}`", "it"))
        problems = self.new_problems()
        self.assertIn(path + " is named in neither " + self.pages["architecture.md"] + " nor " +
                      self.pages["layers.md"], problems)

    def test_a_file_moved_to_another_layer(self):
        path = self.a_file_named_once()
        name = os.path.basename(path)
        layer = path.split("/")[2]
        other = "base" if layer != "base" else "scene"
        moved = f"src/core/{other}/{name}"
        files = [moved if f == path else f for f in self.files]
        problems = self.new_problems(files)
        stale = f"{self.pages['layers.md']}: names {name}, which does not exist in "
        self.assertTrue([p for p in problems if p.startswith(stale) and f"src/core/{layer}/" in p and
                         p.endswith(f"(the tree has {moved})")], problems)
        self.assertIn(moved + " is named in neither " + self.pages["architecture.md"] + " nor " +
                      self.pages["layers.md"], problems)

    def test_names_that_are_not_paths(self):
        self.write("layers.md", self.original["layers.md"].rstrip("\n") +
                   "\n\nThe node publishes `~no_topic` and `/no_tf`, reads `~no/param`, calls "
                   "`f3r_no_function(model)` and `f3r_no_type`, sets `solver.no_field` and "
                   "`modes: none`, and prints `%.*g`.\n")
        self.assertEqual(self.new_problems(), [])

    def test_the_pages_name_something(self):
        tree, named, _ = design_pages.read_pages(list(self.pages.values()), self.files)
        self.assertGreater(len(named & tree.files), 100)
        self.assertIn("src/core/physics", named & tree.dirs)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--junit", help="write the cases as JUnit XML")
    args = ap.parse_args()
    import flex3rpr_tools  # noqa: E402
    return flex3rpr_tools.run_unittest([DesignPages], args.junit, "design_pages")


if __name__ == "__main__":
    sys.exit(main())
