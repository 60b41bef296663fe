#!/usr/bin/env python3
"""Checks that the numbers the docs quote from runs are the numbers the runs produce.

A quoted measurement is marked in the Markdown source right after the number, invisible once rendered:

    157<!--m:mono_detector_nodelet.closed--> of 200<!--m:mono_detector_nodelet.night_frames--> night frames

The key is SOURCE.NAME. SOURCE is a test's result file in catkin's test_results folder without its prefix
(`rosunit-mono_detector_nodelet.xml` -> `mono_detector_nodelet`, `gtest-test_pose_graph.xml` ->
`test_pose_graph`) and NAME one of the properties the test recorded there (gtest `RecordProperty`; a name
recorded by two test cases of one file is quoted as SOURCE.TESTCASE.NAME), or SOURCE names a script's output
given with `--output SOURCE=FILE` and NAME is a `name: value` line of it (`make demo`'s output is `demo`;
its lines after "scored against" are `demo.eval.NAME`; counts in parentheses are `NAME.COUNT_NAME`).
The number must equal the measured value rounded to the digits the doc shows; a key written KEY~TOL accepts
a measured value within TOL of the quoted number (for results that vary from run to run, which the doc says).

A fenced block preceded by `<!--m-block:SOURCE-->` is output of that script: each of its lines, but `...`,
must be a line of the script's output.

What must be marked: every number (outside inline code) in a *measured clause* -- from the word "measured"
to the end of its clause (`;`, the end of the sentence or of an enclosing parenthesis, the word "asserted")
-- and every number in a table column whose header says "measured". A number there that is a constant of
the test (its setup or an assertion's bound) is marked `<!--c-->`. Text between `<!--numbers: WHY-->` and
`<!--/numbers-->` is exempt, for results that no test can reproduce to the digit (timings of `make bench`);
WHY says so in the source.

Usage: check_doc_numbers.py --results DIR [--output SOURCE=FILE]... [--list] DOC.md ...
       check_doc_numbers.py --self-test   (the checker finds a drifted, an unknown and an unmarked number)
Exit status 0 when every marker resolves and matches and no measured number is unmarked; 1 otherwise.
"""
import argparse
import glob
import os
import re
import sys
import xml.etree.ElementTree as ET

NUMBER = r"[-+]?\d+(?:,\d{3})*(?:\.\d+)?"
# A number standing on its own: not part of a word, a file name, a version or a range such as 2-core.
FREE_NUMBER = re.compile(r"(?<![\w.\-/^])" + NUMBER + r"(?![\w\-/]|\.\d)")
MARKER = re.compile(r"(" + NUMBER + r")<!--(m:[\w.\-~ ]+|c)-->")
ANY_MARKER = re.compile(r"<!--(m:[\w.\-~ ]+|c)-->")


def load_results(folder):
    """{key: value} from every result XML's <property> elements: SOURCE.TESTCASE.NAME always, and SOURCE.NAME
    when no other test case of that file recorded NAME with another value."""
    values = {}
    ambiguous = set()
    for path in sorted(glob.glob(os.path.join(folder, "*.xml"))):
        source = re.sub(r"^(rosunit|gtest|rostest)-", "", os.path.basename(path)[:-4])
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError:
            continue
        for case in root.iter("testcase"):
            for prop in case.iter("property"):
                name, value = prop.get("name", ""), prop.get("value", "")
                values[f"{source}.{case.get('name', '')}.{name}"] = value
                short = f"{source}.{name}"
                if short in values and values[short] != value:
                    ambiguous.add(short)
                values[short] = value
    for key in ambiguous:
        del values[key]  # quoting it names the test case
    return values, []


def load_output(source, path):
    """{SOURCE.name: value} from `name: number ...` lines of a script's output, and its lines."""
    values = {}
    if not path or not os.path.exists(path):
        return values, None
    with open(path) as f:
        lines = [line.rstrip("\n") for line in f]
    prefix = source + "."
    for line in lines:
        if line.startswith("scored against"):
            prefix = source + ".eval."
        m = re.match(r"^([a-z_ ]+): (" + NUMBER + r")\b(.*)$", line)
        if m:
            values.setdefault(prefix + m.group(1).strip().replace(" ", "_"), m.group(2))
            # counts in parentheses: "(excluded 50, inconsistent 25, ...)"
            for name, count in re.findall(r"([a-z_]+) (\d+)", m.group(3)):
                values.setdefault(prefix + m.group(1).strip().replace(" ", "_") + "." + name, count)
    return values, lines


def to_float(text):
    return float(text.replace(",", ""))


def matches(quoted, measured, tolerance=None):
    """The quoted number equals the measured one rounded to the quoted number's decimals (or is within
    tolerance of it)."""
    try:
        value = float(measured)
    except ValueError:
        return False
    if tolerance is not None:
        return abs(value - to_float(quoted)) <= tolerance + 1e-12
    digits = len(quoted.split(".")[1]) if "." in quoted else 0
    return round(value, digits) == round(to_float(quoted), digits) or \
        f"{value:.{digits}f}" == f"{to_float(quoted):.{digits}f}"


def strip_code(text):
    """Inline code replaced by spaces of the same length (its numbers are commands and values, not results)."""
    return re.sub(r"`[^`]*`", lambda m: " " * len(m.group(0)), text)


def measured_clauses(text):
    """(start, end) spans of the measured clauses of a paragraph or list item."""
    spans = []
    for m in re.finditer(r"\bmeasured\b", text, re.IGNORECASE):
        depth = 0
        end = len(text)
        i = m.end()
        while i < len(text):
            c = text[i]
            if c == "(":
                depth += 1
            elif c == ")":
                if depth == 0:
                    end = i
                    break
                depth -= 1
            elif c == ";" and depth == 0:
                end = i
                break
            elif c == "." and depth == 0 and (i + 1 == len(text) or text[i + 1] in " \n") and \
                    not text[max(0, i - 3):i].endswith("e.g") and not text[max(0, i - 2):i].endswith("vs"):
                end = i
                break
            elif text.startswith("asserted", i) and depth == 0:
                end = i
                break
            i += 1
        spans.append((m.end(), end))
    return spans


def units(lines):
    """Paragraphs, list items, table rows and fenced blocks of a Markdown file, with their first line number."""
    out = []  # (kind, first_line, text or lines, extra)
    i = 0
    exempt = False
    block_key = None
    while i < len(lines):
        line = lines[i]
        if "<!--numbers:" in line:
            exempt = True
        if "<!--/numbers-->" in line:
            exempt = False
            i += 1
            continue
        m = re.match(r"^\s*<!--m-block:([\w.\-]+)-->\s*$", line)
        if m:
            block_key = m.group(1)
            i += 1
            continue
        if line.lstrip().startswith("```"):
            start = i
            i += 1
            body = []
            while i < len(lines) and not lines[i].lstrip().startswith("```"):
                body.append(lines[i])
                i += 1
            out.append(("code", start + 1, body, block_key))
            block_key = None
            i += 1
            continue
        if line.lstrip().startswith("|"):
            rows = []
            start = i
            while i < len(lines) and lines[i].lstrip().startswith("|"):
                rows.append((i + 1, lines[i]))
                i += 1
            out.append(("table", start + 1, rows, exempt))
            continue
        if not line.strip() or line.startswith("#"):
            out.append(("heading" if line.startswith("#") else "blank", i + 1, line, exempt))
            i += 1
            continue
        start = i
        text = [line]
        i += 1
        while i < len(lines) and lines[i].strip() and not lines[i].startswith("#") and \
                not re.match(r"^\s*([-*]|\d+\.)\s", lines[i]) and not lines[i].lstrip().startswith(("```", "|")):
            text.append(lines[i])
            i += 1
        out.append(("text", start + 1, "\n".join(text), exempt))
    return out


def line_of(first_line, text, offset):
    return first_line + text.count("\n", 0, offset)


def check(doc, values, outputs, listing):
    problems = []
    checked = 0
    with open(doc) as f:
        lines = f.read().split("\n")
    for kind, first, body, extra in units(lines):
        if kind == "code":
            if extra is None:
                continue
            if outputs.get(extra) is None:
                problems.append(f"{doc}:{first}: block marked {extra}: no such output")
                continue
            for n, line in enumerate(body):
                if line.strip() == "...":
                    continue
                checked += 1
                if line not in outputs[extra]:
                    problems.append(f"{doc}:{first + n + 1}: not in the output of {extra}: {line}")
            continue
        if kind == "table":
            header = [c.strip().lower() for c in body[0][1].strip().strip("|").split("|")]
            measured_cols = {k for k, c in enumerate(header) if "measured" in c}
            pieces = []
            for number, row in body[2:]:
                cells = row.strip().strip("|").split("|")
                for k, cell in enumerate(cells):
                    pieces.append((number, cell, k in measured_cols and not extra))
            for number, cell, must in pieces:
                p, c = check_text(doc, number, cell, values, [(0, len(cell))] if must else [], listing)
                problems += p
                checked += c
            continue
        if kind == "text":
            spans = [] if extra else measured_clauses(strip_code(body))
            p, c = check_text(doc, first, body, values, spans, listing)
            problems += p
            checked += c
    return problems, checked


def check_text(doc, first, text, values, spans, listing):
    problems = []
    checked = 0
    for m in MARKER.finditer(text):
        where = f"{doc}:{line_of(first, text, m.start())}"
        quoted, tag = m.group(1), m.group(2)
        if tag == "c":
            continue
        for key in tag[2:].split():
            checked += 1
            key, _, tolerance = key.partition("~")
            if key not in values:
                problems.append(f"{where}: {quoted} quotes {key}, which no test or demo output recorded")
            elif not matches(quoted, values[key], float(tolerance) if tolerance else None):
                problems.append(f"{where}: {quoted} quoted, {values[key]} measured ({key})")
            elif listing:
                print(f"ok {where}: {quoted} = {values[key]} ({key})")
    plain = strip_code(text)
    marked_at = {m.start(1) for m in MARKER.finditer(text)}
    for start, end in spans:
        for m in FREE_NUMBER.finditer(plain, start, end):
            if m.start() in marked_at or ANY_MARKER.match(plain, m.end()):
                continue
            where = f"{doc}:{line_of(first, text, m.start())}"
            context = " ".join(plain[max(0, m.start() - 40):m.end() + 30].split())
            problems.append(f"{where}: measured number {m.group(0)} has no source: ...{context}...")
    return problems, checked


def self_test():
    """The checker on a made-up result file, demo output and doc: it must accept the right numbers and name
    exactly the wrong ones (a check that cannot fail checks nothing)."""
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        with open(os.path.join(tmp, "rosunit-some_test.xml"), "w") as f:
            f.write('<testsuite><testcase name="A"><properties><property name="loops" value="157"/>'
                    '<property name="recall" value="0.785000"/></properties></testcase>'
                    '<testcase name="B"><properties><property name="loops" value="12"/></properties></testcase>'
                    '</testsuite>')
        with open(os.path.join(tmp, "demo.log"), "w") as f:
            f.write("published: 153 loop closures (excluded 50, too_early 60)\nscored against\nrecall: 0.765\n")
        doc = os.path.join(tmp, "doc.md")
        with open(doc, "w") as f:
            f.write("Measured: 157<!--m:some_test.A.loops--> loops (recall 0.785<!--m:some_test.recall-->), "
                    "within 2<!--c--> frames; asserted >= 75 %.\n\n"
                    "Drifted: measured 158<!--m:some_test.A.loops--> loops, 12<!--m:some_test.loops--> ambiguous, "
                    "7<!--m:nothing.there--> unknown, and 9 unmarked; 0.79<!--m:some_test.recall~0.01--> close enough, "
                    "0.80<!--m:some_test.recall~0.01--> not.\n\n"
                    "<!--m-block:demo-->\n```\npublished: 153 loop closures (excluded 50, too_early 60)\n...\n"
                    "recall: 0.766\n```\n\n"
                    "| test | measured | asserted |\n|---|---|---|\n| x | 0.765<!--m:demo.eval.recall--> and 4 | > 3 |\n\n"
                    "<!--numbers: skipped on purpose-->\nMeasured 123 ms.\n<!--/numbers-->\n")
        values, _ = load_results(tmp)
        demo, lines = load_output("demo", os.path.join(tmp, "demo.log"))
        values.update(demo)
        problems, checked = check(doc, values, {"demo": lines}, False)
    expected = ["158 quoted, 157 measured", "12 quotes some_test.loops", "7 quotes nothing.there",
                "measured number 9 has no source", "0.80 quoted, 0.785000 measured", "not in the output of demo: recall: 0.766",
                "measured number 4 has no source"]
    missing = [e for e in expected if not any(e in p for p in problems)]
    if missing or len(problems) != len(expected) or checked != 10:
        print("self-test failed: expected", expected, "got", problems, "checked", checked)
        return 1
    print(f"self-test: the {len(expected)} planted problems found, the right numbers accepted")
    return 0


def main():
    if "--self-test" in sys.argv[1:]:
        return self_test()
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--results", required=True, help="catkin test_results/<package> folder")
    parser.add_argument("--output", action="append", default=[], metavar="SOURCE=FILE",
                        help="a script's output, e.g. demo=build/demo.log")
    parser.add_argument("--list", action="store_true", help="also list every number that matched")
    parser.add_argument("docs", nargs="+")
    args = parser.parse_args()
    values, problems = load_results(args.results)
    outputs = {}
    for item in args.output:
        source, _, path = item.partition("=")
        found, lines = load_output(source, path)
        values.update(found)
        outputs[source] = lines
    checked = 0
    for doc in args.docs:
        p, c = check(doc, values, outputs, args.list)
        problems += p
        checked += c
    for p in problems:
        print(p)
    print(f"doc numbers: {checked} quoted measurements checked in {len(args.docs)} files, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
