"""Counts test cases in the JUnit XML files under one or more folders, each given with the exit
code of the ctest run that wrote it; prints 'N passed, N failed' last. Exits non-zero when any
case failed, no case ran, or a ctest run failed.
usage: count_results.py FOLDER CTEST_RC [FOLDER CTEST_RC ...]"""
import argparse
import pathlib
import sys
import xml.etree.ElementTree as ET

ap = argparse.ArgumentParser(description=__doc__.split("\nusage:")[0])
ap.add_argument("runs", nargs="+", metavar="FOLDER CTEST_RC", help="a results folder and its ctest exit code, in pairs")
args = ap.parse_args()
if len(args.runs) % 2:
    ap.error("FOLDER and CTEST_RC come in pairs")
runs = [(pathlib.Path(f), int(rc)) for f, rc in zip(args.runs[0::2], args.runs[1::2])]
passed = failed = 0
shown = set()  # failure messages printed: each once
for xml in sorted(x for folder, _ in runs for x in folder.rglob("*.xml")):
    try:
        root = ET.parse(xml).getroot()
    except ET.ParseError:
        print(f"unreadable result file {xml}")
        failed += 1
        continue
    for case in root.iter("testcase"):
        if case.find("failure") is not None or case.find("error") is not None:
            failed += 1
            print(f"FAILED {xml.parent.name}/{xml.name}: {case.get('classname')}.{case.get('name')}")
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
        elif case.find("skipped") is None:
            passed += 1
for folder, ctest_rc in runs:
    if ctest_rc != 0 and failed == 0:
        failed = 1
        print(f"ctest in {folder.parent} reported a failure that left no result file (a crash or a timeout)")
print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed or passed == 0 else 0)
