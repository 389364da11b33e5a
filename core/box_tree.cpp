// SPDX-License-Identifier: MIT
#include "core/box_tree.h"

#include <algorithm>

namespace pvs {
namespace {

// The centre a box is sorted by (an empty box has none: the origin, so the order stays strict).
glm::vec3 sort_centre(const Aabb& b) {
    return b.is_empty() ? glm::vec3(0.0f) : b.center();
}

int32_t build_node(const std::vector<Aabb>& boxes, std::vector<uint32_t>& items, size_t lo, size_t hi,
                   int32_t parent, BoxTree& tree) {
    const int32_t id = int32_t(tree.nodes.size());
    tree.nodes.emplace_back();
    Aabb bounds, centres;
    for (size_t i = lo; i < hi; ++i) {
        bounds.extend(boxes[items[i]]);
        centres.extend(sort_centre(boxes[items[i]]));
    }
    tree.nodes[size_t(id)].bounds = bounds;
    tree.nodes[size_t(id)].parent = parent;
    if (hi - lo == 1) {
        tree.nodes[size_t(id)].item = int32_t(items[lo]);
        tree.leaf[items[lo]] = id;
        return id;
    }
    const glm::vec3 ext = centres.size();
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    const size_t mid = (lo + hi) / 2;
    std::nth_element(items.begin() + std::ptrdiff_t(lo), items.begin() + std::ptrdiff_t(mid),
                     items.begin() + std::ptrdiff_t(hi), [&](uint32_t a, uint32_t b) {
                         const float ca = sort_centre(boxes[a])[axis];
                         const float cb = sort_centre(boxes[b])[axis];
                         return ca < cb || (ca == cb && a < b);
                     });
    const int32_t left = build_node(boxes, items, lo, mid, id, tree);
    const int32_t right = build_node(boxes, items, mid, hi, id, tree);
    tree.nodes[size_t(id)].left = left;
    tree.nodes[size_t(id)].right = right;
    return id;
}

}  // namespace

BoxTree BoxTree::build(const std::vector<Aabb>& boxes, const std::vector<uint32_t>* items) {
    std::vector<uint32_t> order;
    if (items) {
        order = *items;
    } else {
        order.resize(boxes.size());
        for (uint32_t i = 0; i < boxes.size(); ++i) order[i] = i;
    }
    BoxTree tree;
    tree.leaf.assign(boxes.size(), -1);
    if (!order.empty()) {
        tree.nodes.reserve(2 * order.size() - 1);
        build_node(boxes, order, 0, order.size(), -1, tree);
    }
    return tree;
}

}  // namespace pvs
