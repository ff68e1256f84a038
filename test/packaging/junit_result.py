"""Writes one JUnit XML result file (what catkin_test_results and scripts/test count)."""
import os
import xml.etree.ElementTree as ET


class Suite:
    """Test cases of one result file: each is a name and a failure message (None = passed)."""

    def __init__(self, name):
        self.name = name
        self.cases = []

    def check(self, case, passed, failure_message):
        """Records `case`; prints and returns the verdict."""
        self.cases.append((case, None if passed else failure_message))
        print("%s %s.%s%s" % ("OK    " if passed else "FAILED", self.name, case,
                              "" if passed else ": " + failure_message))
        return passed

    def write(self, path):
        failures = sum(1 for _, message in self.cases if message is not None)
        suite = ET.Element("testsuite", name=self.name, tests=str(len(self.cases)),
                           failures=str(failures), errors="0")
        for case, message in self.cases:
            element = ET.SubElement(suite, "testcase", classname=self.name, name=case)
            if message is not None:
                ET.SubElement(element, "failure", message=message[:2000]).text = message
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        ET.ElementTree(suite).write(path, encoding="utf-8", xml_declaration=True)
        return failures == 0
