#!/usr/bin/env python3
"""Exit 0 when two output files of `pandora` agree but for timings, run ids and the folder they were
written to; else print the first difference and exit 1 (scripts/same_outputs.sh).

    same_text.py A_FILE B_FILE A_DIR B_DIR

JSON: parsed, the timing keys of tests/cli/same_fields.py dropped at any depth, paths under A_DIR
and B_DIR made relative. HTML (the report): the JSON summaries it embeds compared that way, the
rest with those blocks removed, the numbers of its timing rows ("(s)") and timings in its text
("30.0 ms") masked. Text: timings masked. Tables (a "columns" list beside "rows") lose their
timing columns.
"""
import json
import os
import re
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "cli"))
from same_fields import TIMING_KEYS  # noqa: E402

TIMING = TIMING_KEYS | {"wall_seconds", "peak_rss_mib", "elapsed_s", "seconds_per_iteration"}


def rel(text, folder):
    return text.replace(folder.rstrip("/") + "/", "OUT/")


def strip(x):
    if isinstance(x, dict):
        if isinstance(x.get("columns"), list) and isinstance(x.get("rows"), list):
            # A table (a suggestion's trace): its timing columns dropped.
            keep = [i for i, c in enumerate(x["columns"]) if c not in TIMING]
            x = dict(x, columns=[x["columns"][i] for i in keep],
                     rows=[[r[i] for i in keep] if isinstance(r, list) else r for r in x["rows"]])
        return {k: strip(v) for k, v in x.items() if k not in TIMING}
    if isinstance(x, list):
        return [strip(v) for v in x]
    return x


SCRIPT = re.compile(r'(<script type="application/json"[^>]*>)(.*?)(</script>)', re.S)
TIME_ROW = re.compile(r"^.*\(s\)</t[dh]>.*$", re.M)
TIME_TEXT = re.compile(r"\b\d+(\.\d+)?(e[-+]?\d+)? ?(s|ms|seconds)\b")


def normal(path, folder):
    text = rel(open(path, encoding="utf-8", errors="replace").read(), folder)
    if path.endswith(".json"):
        return ("json", strip(json.loads(text)))
    if path.endswith(".html"):
        blocks = [strip(json.loads(m.group(2))) for m in SCRIPT.finditer(text)]
        rest = SCRIPT.sub(r"\1\3", text)
        rest = TIME_ROW.sub(lambda m: re.sub(r"\d+(\.\d+)?", "_", m.group(0)), rest)
        rest = TIME_TEXT.sub("_t_", rest)
        return ("html", blocks, rest.splitlines())
    return ("text", TIME_TEXT.sub("_t_", text).splitlines())


def first_difference(a, b, where=""):
    if type(a) is not type(b):
        return f"{where}: {type(a).__name__} vs {type(b).__name__}"
    if isinstance(a, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                return f"{where}.{k}: only on one side"
            d = first_difference(a[k], b[k], f"{where}.{k}")
            if d:
                return d
        return None
    if isinstance(a, (list, tuple)):
        if len(a) != len(b):
            return f"{where}: {len(a)} vs {len(b)} items"
        for i, (x, y) in enumerate(zip(a, b)):
            d = first_difference(x, y, f"{where}[{i}]")
            if d:
                return d
        return None
    return None if a == b else f"{where}: {str(a)[:120]!r} vs {str(b)[:120]!r}"


def main():
    a_file, b_file, a_dir, b_dir = sys.argv[1:5]
    d = first_difference(normal(a_file, a_dir), normal(b_file, b_dir))
    if d:
        print(d)
        sys.exit(1)


if __name__ == "__main__":
    main()
