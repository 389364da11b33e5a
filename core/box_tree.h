// SPDX-License-Identifier: MIT
// pvsbake core: a bounding volume hierarchy over boxes, to find the boxes that meet a query box without
// testing every one (docs/ALGORITHMS.md#object-bvh).
//
// One item per leaf; an inner node splits its items at the median of their centres on the longest axis of
// the centres (ties by item index), so the tree depends only on the boxes, never on threads or runs. Nodes
// are in pre-order: a node's children come after it.
#pragma once
#include "core/math.h"

#include <cstdint>
#include <vector>

namespace pvs {

struct BoxTree {
    struct Node {
        Aabb bounds;
        int32_t left = -1, right = -1;  // children, -1 for a leaf
        int32_t item = -1;              // the item of a leaf
        int32_t parent = -1;            // -1 for the root
    };
    std::vector<Node> nodes;    // nodes[0] is the root when not empty
    std::vector<int32_t> leaf;  // per item index < boxes.size(): its leaf, or -1 when not in the tree

    // The tree over boxes[i] for every i in `items` (all of them when `items` is null).
    static BoxTree build(const std::vector<Aabb>& boxes, const std::vector<uint32_t>* items = nullptr);

    // Pre-order walk: `enter(bounds)` decides whether a node is opened; `visit(item)` is called for each
    // leaf opened, so in the tree's order, not the items'.
    template <class Enter, class Visit>
    void walk(Enter&& enter, Visit&& visit) const {
        if (nodes.empty()) return;
        int32_t stack[kMaxDepth];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const Node& node = nodes[size_t(stack[--top])];
            if (!enter(node.bounds)) continue;
            if (node.item >= 0) {
                visit(uint32_t(node.item));
                continue;
            }
            stack[top++] = node.right;
            stack[top++] = node.left;
        }
    }

    // Median splits halve the items, so the depth is about log2(items) + 1; the walk's stack holds one
    // pending sibling per level.
    static constexpr int kMaxDepth = 64;
};

}  // namespace pvs
