"""Counts test cases in the JUnit XML files under one or more folders, each given with the exit
code of the ctest run that wrote it; prints 'N passed, N failed' last. A skipped case (one that
could not run here: catkin_tools missing, a shallow clone) is neither: each is listed as SKIPPED
with its reason, and their count comes before the last line. A failed case is printed
with the name of the folder it was found under (scripts/test gives each CI stage its own folder,
so the last lines of a CI log name the stage that failed). Exits non-zero when any case failed,
no case ran, or a ctest run failed.
usage: count_results.py [--stage NAME] FOLDER CTEST_RC [FOLDER CTEST_RC ...]
  --stage NAME  prints the last line as 'NAME: N passed, N failed' (one stage's count)"""
import argparse
import pathlib
import sys
import xml.etree.ElementTree as ET

ap = argparse.ArgumentParser(description=__doc__.split("\nusage:")[0])
ap.add_argument("--stage", metavar="NAME", help="print the last line as 'NAME: N passed, N failed'")
ap.add_argument("runs", nargs="+", metavar="FOLDER CTEST_RC",
                help="a results folder and its ctest exit code, in pairs")
args = ap.parse_args()
if len(args.runs) % 2:
    ap.error("FOLDER and CTEST_RC come in pairs")
stage = args.stage
runs = [(pathlib.Path(f), int(rc)) for f, rc in zip(args.runs[0::2], args.runs[1::2])]


def label(folder):
    """The folder's name under stage_results/ (the stage, and the workspace within it)."""
    parts = folder.parts
    return "/".join(parts[parts.index("stage_results") + 1:]) if "stage_results" in parts else folder.name


passed = failed = 0
skipped = []  # (where, why)
shown = set()  # failure messages printed: each once
for folder, ctest_rc in runs:
    failed_here = failed
    for xml in sorted(folder.rglob("*.xml")):
        try:
            root = ET.parse(xml).getroot()
        except ET.ParseError:
            print(f"unreadable result file [{label(folder)}] {xml}")
            failed += 1
            continue
        for case in root.iter("testcase"):
            if case.find("failure") is not None or case.find("error") is not None:
                failed += 1
                print(f"FAILED [{label(folder)}] {xml.parent.name}/{xml.name}: "
                      f"{case.get('classname')}.{case.get('name')}")
                # the first lines of the message, so that a CI log's tail says why
                node = case.find("failure") if case.find("failure") is not None else case.find("error")
                text = (node.get("message") or "") + "\n" + (node.text or "")
                lines = tuple(dict.fromkeys(l.strip() for l in text.splitlines() if l.strip()))[:12]
                if lines in shown:
                    print("    (the message above)")
                else:
                    for line in lines:
                        print(f"    {line[:300]}")
                    shown.add(lines)
            elif case.find("skipped") is not None:
                skipped.append((f"[{label(folder)}] {xml.parent.name}/{xml.name}: "
                                f"{case.get('classname')}.{case.get('name')}",
                                case.find("skipped").get("message") or ""))
            else:
                passed += 1
    if ctest_rc != 0 and failed == failed_here:
        failed += 1
        print(f"FAILED [{label(folder)}] a run exited with {ctest_rc} but left no failed case: "
              f"a crash or a timeout (see its log under build/)")
for where, why in skipped:
    print(f"SKIPPED {where}: {why}")
if skipped:
    print(f"{stage + ': ' if stage else ''}{len(skipped)} skipped (neither passed nor failed)")
print(f"{stage + ': ' if stage else ''}{passed} passed, {failed} failed")
sys.exit(1 if failed or passed == 0 else 0)
