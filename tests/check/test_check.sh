#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# check_demo_on must abort (non-zero exit) with numeric/check.h's one line naming the condition.
# Usage: test_check.sh CHECK_DEMO_ON
out=$("$1" 2>&1)
status=$?
echo "$out"
[ "$status" -ne 0 ] || { echo "FAILED: a false IMPULSE_DCHECK did not stop the program"; exit 1; }
grep -qF 'impulse: invariant failed: (++evaluated, argc < 0) (' <<<"$out" ||
    { echo "FAILED: not the one line naming the condition"; exit 1; }
echo "PASSED"
