// SPDX-License-Identifier: MIT
// The box tree (core/box_tree.h) against a scan of every box: a walk that opens the nodes meeting a query
// box visits exactly the boxes a scan finds; and the tree's links (leaves, parents, pre-order) hold.
#include "core/box_tree.h"
#include "core/random.h"
#include "tests/random_boxes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace pvs {
namespace {

using test::random_box;

TEST(BoxTree, AWalkFindsWhatAScanFinds) {
    Rng rng(17, 3);
    for (int scene = 0; scene < 8; ++scene) {
        std::vector<Aabb> boxes;
        const int n = 1 + int(rng.below(900));
        for (int i = 0; i < n; ++i) boxes.push_back(random_box(rng, 100.0f, scene % 2 ? 2.0f : 30.0f));
        if (scene == 3) boxes[0] = Aabb{};  // an empty box is kept, and meets nothing
        // Every other box only, in one scene: the others are not in the tree.
        std::vector<uint32_t> items;
        for (uint32_t i = 0; i < boxes.size(); i += scene == 5 ? 2 : 1) items.push_back(i);
        const BoxTree tree = BoxTree::build(boxes, &items);
        ASSERT_EQ(tree.nodes.size(), 2 * items.size() - 1);
        for (uint32_t i = 0; i < boxes.size(); ++i) {
            const bool in = std::find(items.begin(), items.end(), i) != items.end();
            ASSERT_EQ(tree.leaf[i] >= 0, in) << i;
            if (in) {
                EXPECT_EQ(tree.nodes[size_t(tree.leaf[i])].item, int32_t(i));
            }
        }
        for (size_t k = 0; k < tree.nodes.size(); ++k) {
            const BoxTree::Node& node = tree.nodes[k];
            if (k > 0) {
                EXPECT_LT(node.parent, int32_t(k)) << "children come after their parent";
            }
            if (node.item >= 0) continue;
            for (int32_t c : {node.left, node.right}) {
                EXPECT_GT(c, int32_t(k));
                EXPECT_EQ(tree.nodes[size_t(c)].parent, int32_t(k));
                const Aabb& b = tree.nodes[size_t(c)].bounds;
                if (!b.is_empty()) {
                    EXPECT_TRUE(node.bounds.overlaps(b));
                }
            }
        }
        for (int q = 0; q < 50; ++q) {
            const Aabb query = random_box(rng, 100.0f, 40.0f);
            std::vector<uint32_t> walked, scanned;
            tree.walk([&](const Aabb& b) { return b.overlaps(query); },
                      [&](uint32_t i) { walked.push_back(i); });
            for (uint32_t i : items)
                if (boxes[i].overlaps(query)) scanned.push_back(i);
            std::sort(walked.begin(), walked.end());
            EXPECT_EQ(walked, scanned) << "scene " << scene << " query " << q;
        }
    }
    EXPECT_TRUE(BoxTree::build({}).nodes.empty());
}

}  // namespace
}  // namespace pvs
