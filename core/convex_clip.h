// pvsbake core: a convex polygon cut by an axis plane (Sutherland-Hodgman), for the shaft pass's pieces
// (pvs/shaft_hiding.cpp) and the world edits of the samples (samples/world_edit.cpp).
#pragma once

#include <vector>

namespace pvs {

// The part of convex `in` (2D or 3D points of doubles) on one side of x[k] = at (keep_below: x[k] <= at),
// closed. Corners made on the line get exactly `at` there, so pieces cut by a rectangle's side meet the
// next rectangle's side exactly where the two sides coincide.
template <class P>
void clip(const std::vector<P>& in, int k, double at, bool keep_below, std::vector<P>& out) {
    out.clear();
    const size_t n = in.size();
    for (size_t i = 0; i < n; ++i) {
        const P& a = in[i];
        const P& b = in[(i + 1) % n];
        const bool a_in = keep_below ? a[k] <= at : a[k] >= at;
        const bool b_in = keep_below ? b[k] <= at : b[k] >= at;
        if (a_in) out.push_back(a);
        if (a_in != b_in && a[k] != at && b[k] != at) {
            P y = a + (at - a[k]) / (b[k] - a[k]) * (b - a);
            y[k] = at;
            out.push_back(y);
        }
    }
}

}  // namespace pvs
