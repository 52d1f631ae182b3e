#!/usr/bin/env python3
"""The code's two mechanical habits (CONTRIBUTING.md), checked by ctest (style.*) and so by CI.

  scripts/check_style.py format          every tracked C++ file as the repository's .clang-format
                                         writes it (clang-format --dry-run -Werror); lists the
                                         files that differ and exits 1.
  scripts/check_style.py function-size   no function longer than LIMIT lines (signature to closing
                                         brace, comments and blank lines included), lambdas counted
                                         in their function and on their own, GoogleTest bodies
                                         (TEST, TEST_F, TEST_P) included. Functions found by
                                         universal-ctags.
Run from anywhere; it reads the git checkout it lives in.
"""
import os
import re
import subprocess
import sys

LIMIT = 150
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def tracked_cpp():
    out = subprocess.check_output(['git', '-C', ROOT, 'ls-files', '*.cpp', '*.h'], text=True)
    return [f for f in out.split() if not f.startswith('tests/fuzz/corpus/')]


def check_format():
    files = tracked_cpp()
    bad = []
    # In chunks: one clang-format process per few dozen files keeps the command line short.
    for i in range(0, len(files), 40):
        chunk = files[i:i + 40]
        r = subprocess.run(['clang-format', '--dry-run', '-Werror', '--style=file'] + chunk, cwd=ROOT,
                           capture_output=True, text=True)
        if r.returncode != 0:
            bad += sorted({line.split(':')[0] for line in r.stderr.splitlines()
                           if ': error:' in line or ': warning:' in line})
    if bad:
        print('style.format: %d file(s) differ from .clang-format; run\n  clang-format -i %s'
              % (len(bad), ' '.join(bad)))
        return 1
    print('style.format: %d files formatted as .clang-format says' % len(files))
    return 0


def strip_code(text):
    """The text with comments and string/character literals blanked (newlines kept), so braces
    inside them do not count."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith('//', i):
            j = text.find('\n', i)
            j = n if j < 0 else j
            out.append(' ' * (j - i))
            i = j
        elif text.startswith('/*', i):
            j = text.find('*/', i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == '_')):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = text.find(')' + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        elif c in '"\'':
            j = i + 1
            while j < n and text[j] != c and text[j] != '\n':
                j += 2 if text[j] == '\\' else 1
            j = min(j + 1, n)
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return ''.join(out)


def test_bodies(path):
    """(name, first line, last line) of each GoogleTest body in `path`."""
    with open(os.path.join(ROOT, path), encoding='utf-8') as f:
        code = strip_code(f.read())
    lines = code.split('\n')
    found = []
    for i, line in enumerate(lines):
        m = re.match(r'^(TEST|TEST_F|TEST_P|TYPED_TEST)\(\s*(\w+)\s*,\s*(\w+)', line)
        if not m:
            continue
        depth, started = 0, False
        for j in range(i, len(lines)):
            for ch in lines[j]:
                if ch == '{':
                    depth += 1
                    started = True
                elif ch == '}':
                    depth -= 1
            if started and depth == 0:
                break
        found.append(('%s.%s' % (m.group(2), m.group(3)), i + 1, j + 1))
    return found


def functions():
    """{(path, name): lines} of every function longer than LIMIT lines (the longest of a name)."""
    files = tracked_cpp()
    out = subprocess.run(['ctags', '-o', '-', '--languages=C++', '--kinds-C++=f', '--fields=+neK',
                          '--extras=-q', '-x', '--_xformat=%F\t%n\t%e\t%{scope}\t%N\t%K'] + files,
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout
    long = {}
    for line in out.splitlines():
        parts = line.split('\t')
        if len(parts) < 6 or parts[5] != 'function' or not parts[2].isdigit():
            continue
        path, start, end = parts[0], int(parts[1]), int(parts[2])
        # ctags calls anonymous namespaces and lambdas __anon<hash>: dropped from the scope (a
        # namespace), "(lambda)" as the name.
        scope = [s for s in parts[3].split('::') if s and not s.startswith('__anon')]
        name = '::'.join(scope + [re.sub(r'^__anon[0-9a-f]+$', '(lambda)', parts[4])])
        n = end - start + 1
        if n > LIMIT:
            long[(path, name)] = max(n, long.get((path, name), 0))
    for path in files:
        if path.endswith('_test.cpp') or '/tests/' in '/' + path:
            for name, start, end in test_bodies(path):
                n = end - start + 1
                if n > LIMIT:
                    long[(path, name)] = max(n, long.get((path, name), 0))
    return long


def check_function_size():
    long = functions()
    for (path, name), n in sorted(long.items()):
        print('%s: %s is %d lines, over the limit of %d: split it' % (path, name, n, LIMIT))
    if long:
        return 1
    print('style.function_size: no function over %d lines' % LIMIT)
    return 0


def main(argv):
    if len(argv) >= 2 and argv[1] == 'format':
        return check_format()
    if len(argv) >= 2 and argv[1] == 'function-size':
        return check_function_size()
    print(__doc__)
    return 2


if __name__ == '__main__':
    sys.exit(main(sys.argv))
