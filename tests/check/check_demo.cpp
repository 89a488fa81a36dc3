// SPDX-License-Identifier: Apache-2.0
// numeric/check.h shown working both ways (CTest check_dcheck_on, check_dcheck_off): an
// IMPULSE_DCHECK whose condition is false aborts with its one line where IMPULSE_DCHECKS is
// defined, and where it is not, the condition is not even evaluated (release frames keep their
// bits). The condition counts its evaluations; argc > 0 always, so it is false.
#include <cstdio>

#include "numeric/check.h"

int main(int argc, char**) {
    int evaluated = 0;
    IMPULSE_DCHECK((++evaluated, argc < 0));
    std::printf("IMPULSE_DCHECK did not fire; its condition was evaluated %d times\n", evaluated);
    return evaluated;
}
