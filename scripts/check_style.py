#!/usr/bin/env python3
"""The code's two mechanical habits (CONTRIBUTING.md), checked by ctest (style.*) and so by CI.

  scripts/check_style.py format          every tracked C++ file as the repository's .clang-format
                                         writes it (clang-format --dry-run -Werror); lists the
                                         files that differ and exits 1.
  scripts/check_style.py function-size   no function longer than LIMIT lines (signature to closing
                                         brace, comments and blank lines included), GoogleTest
                                         bodies (TEST, TEST_F, TEST_P) included. Functions found by
                                         universal-ctags. The functions listed in
                                         scripts/function_size_allowlist.txt were over the limit
                                         when the check came in: each may shrink, never grow, and
                                         must leave the list once it is within the limit, so the
                                         list only gets shorter.
  scripts/check_style.py function-size --write-allowlist
                                         rewrites the allowlist from the tree (only to shorten it).
Run from anywhere; it reads the git checkout it lives in.
"""
import os
import re
import subprocess
import sys

LIMIT = 150
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ALLOWLIST = os.path.join(ROOT, 'scripts', 'function_size_allowlist.txt')


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


def read_allowlist():
    allowed = {}
    if os.path.exists(ALLOWLIST):
        with open(ALLOWLIST, encoding='utf-8') as f:
            for line in f:
                line = line.strip()
                if not line or line.startswith('#'):
                    continue
                lines, path, name = line.split(None, 2)
                allowed[(path, name)] = int(lines)
    return allowed


def check_function_size(write):
    long = functions()
    if write:
        allowed = read_allowlist()
        grown = [k for k in long if k not in allowed or long[k] > allowed[k]]
        if grown and os.path.exists(ALLOWLIST):
            print('refusing to write: the allowlist may only shrink; over the limit and new or grown: '
                  + ', '.join('%s %s (%d)' % (k[0], k[1], long[k]) for k in grown))
            return 1
        with open(ALLOWLIST, 'w', encoding='utf-8') as f:
            f.write('# Functions over %d lines when scripts/check_style.py came in (issue 28): lines, file,\n'
                    '# function. Each may shrink, never grow; split one and take its line out. Never add one.\n'
                    % LIMIT)
            for (path, name), n in sorted(long.items(), key=lambda kv: (-kv[1], kv[0])):
                f.write('%d %s %s\n' % (n, path, name))
        print('wrote %s: %d functions' % (ALLOWLIST, len(long)))
        return 0
    allowed = read_allowlist()
    errors = []
    for (path, name), n in sorted(long.items()):
        if (path, name) not in allowed:
            errors.append('%s: %s is %d lines, over the limit of %d: split it' % (path, name, n, LIMIT))
        elif n > allowed[(path, name)]:
            errors.append('%s: %s grew to %d lines (listed at %d, over the limit of %d): split it'
                          % (path, name, n, allowed[(path, name)], LIMIT))
    for (path, name), n in sorted(allowed.items()):
        if (path, name) not in long:
            errors.append('%s: %s is within %d lines now (or gone): take its line out of %s'
                          % (path, name, LIMIT, os.path.relpath(ALLOWLIST, ROOT)))
        elif long[(path, name)] < n:
            errors.append('%s: %s shrank to %d lines: lower its line in %s to %d'
                          % (path, name, long[(path, name)], os.path.relpath(ALLOWLIST, ROOT),
                             long[(path, name)]))
    if errors:
        print('\n'.join(errors))
        return 1
    print('style.function_size: no function over %d lines but the %d listed, none grown'
          % (LIMIT, len(allowed)))
    return 0


def main(argv):
    if len(argv) >= 2 and argv[1] == 'format':
        return check_format()
    if len(argv) >= 2 and argv[1] == 'function-size':
        return check_function_size('--write-allowlist' in argv[2:])
    print(__doc__)
    return 2


if __name__ == '__main__':
    sys.exit(main(sys.argv))
