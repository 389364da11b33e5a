// SPDX-License-Identifier: MIT
// pvsbake core: a convex polygon cut by an axis plane or by any line (Sutherland-Hodgman), for the shaft
// pass's pieces (pvs/shaft_hiding.cpp) and the world edits of the samples (samples/world_edit.cpp).
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

// The part of convex 2D `in` on the left of the directed line a -> b, or on it (cross(b - a, p - a) >= 0;
// keep_right: <= 0), closed. A corner exactly on the line (cross 0) stays as it is, so two pieces cut along
// the same line, or along a line through the same two points, meet exactly.
template <class P>
void clip_line(const std::vector<P>& in, const P& a, const P& b, bool keep_right, std::vector<P>& out) {
    out.clear();
    const size_t n = in.size();
    const P d = b - a;
    const auto side = [&](const P& p) {
        const double s = d.x * (p.y - a.y) - d.y * (p.x - a.x);
        return keep_right ? -s : s;
    };
    for (size_t i = 0; i < n; ++i) {
        const P& p = in[i];
        const P& q = in[(i + 1) % n];
        const double sp = side(p), sq = side(q);
        if (sp >= 0.0) out.push_back(p);
        if ((sp > 0.0 && sq < 0.0) || (sp < 0.0 && sq > 0.0)) out.push_back(p + (sp / (sp - sq)) * (q - p));
    }
}

}  // namespace pvs
