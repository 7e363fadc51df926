"""Checks a Keel report.html against its report.json (run with Debian's /usr/bin/python3).

usage: report_html_check.py REPORT_JSON REPORT_HTML [--expect POINTER ...] [--expect-id ID ...]

1. The page is well-formed XML (xml.etree) and parses as HTML (html.parser).
2. Nothing in it can fetch or run anything: no script, no element that loads a resource, no
   event-handler attribute, no URL scheme, no CSS url() or @import, links only to #anchors.
3. Every leaf of report.json is a row of the page's "every figure" table (#all-figures), keyed
   by its JSON pointer, with the same value: numbers as <data value="..."> equal to the JSON
   number (the same double, or the same integer), strings, booleans and nulls as text.
4. Every <data data-pointer="P" value="V"> anywhere in the page shows report.json's value at P,
   so no figure in the tables is wrong.
5. Each --expect POINTER is shown by a <data> element outside the "every figure" table (the
   stage sections show it), and each --expect-id ID is an element id of the page.
Prints what it checked; exits 1 with the list of problems.
"""

import html.parser
import json
import math
import re
import sys
import xml.etree.ElementTree as ET

ALLOWED_ELEMENTS = {
    "html", "head", "meta", "title", "style", "body", "h1", "h2", "h3", "p", "section", "table",
    "caption", "thead", "tbody", "tr", "th", "td", "data", "code", "strong", "details",
    "summary", "figure", "figcaption", "div", "ul", "li", "svg", "line", "text", "rect",
    "polyline", "circle", "a", "span",
}
FORBIDDEN_TEXT = [r"https?:", r"ftp:", r"file:", r"javascript:", r"data:", r"url\(", r"@import",
                  r"<script", r"//[a-z0-9.-]+\.[a-z]{2,}"]


def pointer_token(key):
    return key.replace("~", "~0").replace("/", "~1")


def leaves(value, pointer=""):
    if isinstance(value, dict) and value:
        for key, child in value.items():
            yield from leaves(child, pointer + "/" + pointer_token(key))
    elif isinstance(value, list) and value:
        for i, child in enumerate(value):
            yield from leaves(child, pointer + "/" + str(i))
    else:
        yield pointer, value


def resolve(document, pointer):
    value = document
    for token in pointer.split("/")[1:]:
        token = token.replace("~1", "/").replace("~0", "~")
        if isinstance(value, list):
            value = value[int(token)]
        else:
            value = value[token]
    return value


def same_number(text, value):
    if value is None:
        return text == "null"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    if isinstance(value, int):
        return re.fullmatch(r"-?[0-9]+", text) is not None and int(text) == value
    try:
        parsed = float(text)
    except ValueError:
        return False
    return parsed == value or (math.isnan(parsed) and math.isnan(value))


class Page(html.parser.HTMLParser):
    """Collects elements, attributes, data elements and the rows of #all-figures."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.problems = []
        self.ids = set()
        self.data = []  # (pointer or None, value, inside #all-figures)
        self.rows = {}  # pointer -> (cell text, [data values])
        self.stack = []
        self.in_all = 0
        self.cells = None
        self.cell_text = None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag not in ALLOWED_ELEMENTS:
            self.problems.append("element <%s> is not allowed" % tag)
        for name, value in attrs.items():
            if name.startswith("on") or name in ("src", "srcset", "action", "formaction",
                                                 "background", "poster", "xlink:href"):
                self.problems.append("attribute %s on <%s>" % (name, tag))
            if name == "href" and not (value or "").startswith("#"):
                self.problems.append("link to %r" % value)
        if "id" in attrs:
            self.ids.add(attrs["id"])
        if tag == "table" and attrs.get("id") == "all-figures":
            self.in_all = len(self.stack) + 1
        if tag == "data":
            self.data.append((attrs.get("data-pointer"), attrs.get("value"), bool(self.in_all)))
            if self.cells is not None:
                self.cells[-1][1].append(attrs.get("value"))
        if self.in_all and tag == "tr":
            self.cells = []
        if self.cells is not None and tag == "td":
            self.cells.append(["", []])
        self.stack.append(tag)

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.problems.append("</%s> does not close <%s>" % (tag, self.stack[-1:]))
            return
        self.stack.pop()
        if self.in_all and tag == "tr" and self.cells is not None:
            if len(self.cells) == 2:
                self.rows[self.cells[0][0]] = (self.cells[1][0], self.cells[1][1])
            self.cells = None
        if self.in_all and tag == "table" and len(self.stack) + 1 == self.in_all:
            self.in_all = 0

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        self.handle_endtag(tag)

    def handle_data(self, text):
        if self.cells:
            self.cells[-1][0] += text


def expected_text(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if value is None:
        return "\u2014"
    if isinstance(value, str):
        return value
    if isinstance(value, list):
        return "[]"
    if isinstance(value, dict):
        return "{}"
    return None  # a number: compared through its <data> element


def main(argv):
    if len(argv) < 3:
        print(__doc__)
        return 2
    report = json.load(open(argv[1], encoding="utf-8"))
    text = open(argv[2], encoding="utf-8").read()
    expect, expect_ids = [], []
    rest = argv[3:]
    while rest:
        flag, value, rest = rest[0], rest[1], rest[2:]
        (expect if flag == "--expect" else expect_ids).append(value)

    problems = []
    # 1. Well-formed XML (the doctype is not XML) and HTML.
    try:
        ET.fromstring(re.sub(r"^<!DOCTYPE html>\s*", "", text))
    except ET.ParseError as e:
        problems.append("not well-formed: %s" % e)
    page = Page()
    page.feed(text)
    page.close()
    problems += page.problems
    # 2. Nothing to fetch or run.
    for pattern in FORBIDDEN_TEXT:
        for match in re.finditer(pattern, text, re.IGNORECASE):
            problems.append("forbidden %r at offset %d: %r" %
                            (pattern, match.start(), text[max(0, match.start() - 40):match.end() + 40]))
    # 3. Every leaf in the "every figure" table with its value.
    checked = 0
    for pointer, value in leaves(report):
        row = page.rows.get(pointer)
        if row is None:
            problems.append("%s: not in #all-figures" % pointer)
            continue
        cell_text, values = row
        want = expected_text(value)
        if want is None:
            ok = len(values) == 1 and same_number(values[0], value)
        elif value is None and values:  # a NaN figure, which report.json writes as null
            ok = values == ["null"]
        else:
            ok = cell_text.strip() == want.strip()
        if not ok:
            problems.append("%s: page shows %r %r, report.json has %r" %
                            (pointer, cell_text, values, value))
        checked += 1
    # 4. Every number that names its figure shows report.json's value.
    shown = 0
    for pointer, value, _ in page.data:
        if pointer is None:
            continue
        try:
            truth = resolve(report, pointer)
        except (KeyError, IndexError, ValueError):
            problems.append("data-pointer %s: no such figure in report.json" % pointer)
            continue
        if not same_number(value, truth):
            problems.append("data-pointer %s: page %r, report.json %r" % (pointer, value, truth))
        shown += 1
    # 5. The stage sections show the expected figures and elements.
    in_sections = {p for p, _, inside in page.data if p is not None and not inside}
    for pointer in expect:
        if pointer not in in_sections:
            problems.append("%s: not shown in a stage section" % pointer)
    for element_id in expect_ids:
        if element_id not in page.ids:
            problems.append("no element with id %r" % element_id)

    print("report_html_check: %d leaves of report.json, %d numbers with pointers (%d in stage "
          "sections), %d expected figures, %d ids, %d bytes" %
          (checked, shown, len([1 for p, _, inside in page.data if p and not inside]),
           len(expect), len(expect_ids), len(text)))
    for problem in problems[:50]:
        print("PROBLEM: " + problem)
    if len(problems) > 50:
        print("... and %d more" % (len(problems) - 50))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
