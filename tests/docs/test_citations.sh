#!/bin/bash
# SPDX-License-Identifier: MIT
# The citation check (tests/docs/check_citations.py) shown able to fail: on a file of bogus
# citations it must exit 1 and name each one, and it must not report the good ones beside them.
set -u
root=${1:?usage: test_citations.sh SOURCE_DIR}
python=${PYTHON:-python3}
here=$root/tests/docs
out=$("$python" "$here/check_citations.py" "$root" "$here/bogus_citations.txt")
status=$?
fail=0
if [ "$status" -ne 1 ]; then echo "expected exit 1 on bogus citations, got $status"; fail=1; fi
for expected in \
    "bogus_citations.txt:3: nowhere.md: no such document" \
    "bogus_citations.txt:4: design.md: no section §99" \
    "bogus_citations.txt:5: docs/perspective.md: no section §42" \
    "bogus_citations.txt:6: docs/perspective.md: no equation (77.7)" \
    "bogus_citations.txt:7: docs/scenes.md: no section or paragraph \"No such section\"" \
    "bogus_citations.txt:8: docs/solid.md: no section or paragraph \"Slabs\"" \
    "8 citations checked, 6 broken"; do
    if ! grep -qF -- "$expected" <<<"$out"; then echo "missing from the report: $expected"; fail=1; fi
done
if [ "$(grep -c 'bogus_citations.txt' <<<"$out")" -ne 6 ]; then
    echo "expected exactly 6 broken citations reported:"; fail=1
fi
[ "$fail" -eq 0 ] || { echo "--- report:"; echo "$out"; exit 1; }
echo "check_citations.py reports each of 6 bogus citations and none of the 2 good ones"
