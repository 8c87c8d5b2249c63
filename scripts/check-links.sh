#!/usr/bin/env bash
# Checks that every relative link and image of the Markdown pages points to an
# existing file: [text](path), ![alt](path), with #anchors stripped; web links
# and in-page anchors are skipped, and so are fenced code blocks.
#   scripts/check-links.sh              every *.md of the repository
#   scripts/check-links.sh A.md B.md    only these pages
# Exit 1 and one line per broken link (page:line: target) if any is broken.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -eq 0 ]; then
  mapfile -t pages < <(git ls-files '*.md' 2>/dev/null || find . -name '*.md' -not -path './build*')
else
  pages=("$@")
fi
python3 - "${pages[@]}" <<'PY'
import os, re, sys
link = re.compile(r'!?\[[^\]]*\]\(([^)\s]+)(?:\s+"[^"]*")?\)')
bad = 0
for page in sys.argv[1:]:
    fence = False
    with open(page, encoding='utf-8') as f:
        for n, line in enumerate(f, 1):
            if line.lstrip().startswith('```'):
                fence = not fence
                continue
            if fence:
                continue
            for target in link.findall(line):
                if re.match(r'^[a-z]+:', target) or target.startswith('#'):
                    continue
                path = target.split('#', 1)[0]
                if not os.path.exists(os.path.join(os.path.dirname(page), path)):
                    print(f'{page}:{n}: {target}')
                    bad += 1
print(f'check-links: {len(sys.argv) - 1} pages, {bad} broken links', file=sys.stderr)
sys.exit(1 if bad else 0)
PY
