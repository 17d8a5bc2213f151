#!/usr/bin/env python3
# Function bodies longer than 150 lines in ext/ and tools/ (not tests), from
# the signature to the closing brace, longest first: issue 33's list of bodies
# still to split. Run from the repository root: scripts/long_bodies.py
import glob
import re
res = []
files = [f for f in glob.glob('ext/*/*.cc') + glob.glob('tools/*.cc') if not f.endswith('_test.cc')]
for f in files:
    lines = open(f).read().split('\n')
    i = 0
    while i < len(lines):
        l = lines[i]
        # function definition start at column 0, not namespace/struct
        if re.match(r'^[A-Za-z].*[\w>&*]\s*[\w:~<>]+\(', l) and not l.startswith(('namespace', 'struct', 'class', 'using', 'typedef', 'enum', 'template')) and not l.rstrip().endswith(';'):
            # find opening brace line
            j = i
            while j < len(lines) and '{' not in lines[j] and not lines[j].rstrip().endswith(';'):
                j += 1
            if j < len(lines) and '{' in lines[j]:
                depth = 0; k = j
                while k < len(lines):
                    depth += lines[k].count('{') - lines[k].count('}')
                    if depth == 0: break
                    k += 1
                n = k - i + 1
                m = re.search(r'([\w:~]+)\(', l)
                if n > 150: res.append((n, f, m.group(1) if m else l))
                i = k + 1; continue
        i += 1
for n, f, name in sorted(res, reverse=True): print(n, f, name)
print(len(res))
