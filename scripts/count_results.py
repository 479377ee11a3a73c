"""Counts test cases in the JUnit XML files under a folder; prints 'N passed, N failed' last.
Exits non-zero when any case failed, no case ran, or ctest itself failed."""
import pathlib
import sys
import xml.etree.ElementTree as ET

folder, ctest_rc = pathlib.Path(sys.argv[1]), int(sys.argv[2])
passed = failed = 0
for xml in sorted(folder.rglob("*.xml")):
    try:
        root = ET.parse(xml).getroot()
    except ET.ParseError:
        print(f"unreadable result file {xml}")
        failed += 1
        continue
    for case in root.iter("testcase"):
        if case.find("failure") is not None or case.find("error") is not None:
            failed += 1
            print(f"FAILED {xml.name}: {case.get('classname')}.{case.get('name')}")
        elif case.find("skipped") is None:
            passed += 1
if ctest_rc != 0 and failed == 0:
    failed = 1
    print("ctest reported a failure that left no result file (a crash or a timeout)")
print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed or passed == 0 else 0)
