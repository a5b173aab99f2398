#!/usr/bin/env python3
"""tools/recovery_cascades.py LDC KIND 'GLOB[,GLOB...]' [N] [SEED] -- how many errors one mistake gives.

Makes N (default 300) mutants of the files GLOB matches, each with one random
single-line mistake (the line deleted, a token inserted, or up to six characters
deleted), runs `LDC FILE -fsyntax-only -w` on each (KIND project: `--project`), and
prints how many mutants reported 0, 1, 2, ... errors (docs/diagnostics.md).  A
mutant of a project is written beside its project, so its program files are found.
"""
import collections, glob, os, random, subprocess, sys, tempfile

ldc, kind, pattern = sys.argv[1], sys.argv[2], sys.argv[3]
count = int(sys.argv[4]) if len(sys.argv) > 4 else 300
random.seed(int(sys.argv[5]) if len(sys.argv) > 5 else 7)
files = [f for p in pattern.split(',') for f in sorted(glob.glob(p)) if os.path.getsize(f) < 20000]
tokens = ['(', ')', ';', ',', 'if', 'fi', 'then', 'else', '#if 1', '#endif', 'END', 'RUNG', 'SERIES', 'PARALLEL',
          'step', 'transition', 'select', 'parallel', 'branch', 'end', 'jump', 'N', '{', '}', 'task', 'program',
          'resource', '@', 'x', '0']
hist = collections.Counter()
tmp = tempfile.mkdtemp()
for n in range(count):
    f = random.choice(files)
    src = open(f, 'rb').read().decode('latin1').split('\n')
    i = random.randrange(len(src))
    r = random.random()
    if r < 0.3:
        del src[i]
    elif r < 0.7:
        j = random.randint(0, len(src[i]))
        src[i] = src[i][:j] + random.choice(tokens) + src[i][j + random.randint(0, 3):]
    else:
        j = random.randint(0, len(src[i]))
        src[i] = src[i][:j] + src[i][j + random.randint(1, 6):]
    where = os.path.dirname(f) if kind == 'project' else tmp
    mutant = os.path.join(where, 'zz_mutant' + os.path.splitext(f)[1])
    open(mutant, 'w', encoding='latin1').write('\n'.join(src))
    args = [ldc] + (['--project', mutant] if kind == 'project' else [mutant]) + ['-fsyntax-only', '-w']
    out = subprocess.run(args, capture_output=True, text=True, errors='replace').stderr
    hist[out.count(': error: ')] += 1
    os.remove(mutant)
os.rmdir(tmp)
print(kind, ' '.join('%d errors: %d' % kv for kv in sorted(hist.items())))
