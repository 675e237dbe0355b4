#include "strategies/bvh/bvh.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace ccd::bvh {

Box3 swept_face_box(const Face& face, std::span<const Vec3> x0, std::span<const Vec3> x1, double inflation) {
  Box3 box;
  for (VertexId v : face) {
    box.extend(x0[v]);
    box.extend(x1[v]);
  }
  return widened(box, inflation);
}

void TriangleBvh::build(const MeshTopology& topology, FaceId first_face, std::size_t face_count, std::span<const Vec3> x) {
  first_face_ = first_face;
  nodes_.clear();
  bottom_up_.clear();
  leaf_of_face_.assign(face_count, -1);
  if (face_count == 0) return;
  std::vector<FaceId> order(face_count);
  std::iota(order.begin(), order.end(), first_face);
  std::vector<Vec3> centroid(face_count);
  for (std::size_t i = 0; i < face_count; ++i) {
    const Face& f = topology.face(first_face + static_cast<FaceId>(i));
    centroid[i] = (x[f[0]] + x[f[1]] + x[f[2]]) / 3.0;
  }
  struct Task {
    std::int32_t node;
    std::size_t first, count;
    int depth;
  };
  nodes_.push_back({});
  depth_ = 0;
  std::vector<Task> tasks{{0, 0, face_count, 0}};
  std::vector<std::int32_t> top_down;
  while (!tasks.empty()) {
    const Task task = tasks.back();
    tasks.pop_back();
    Node& node = nodes_[static_cast<std::size_t>(task.node)];
    if (task.count == 1) {
      depth_ = std::max(depth_, task.depth);
      node.face = order[task.first];
      leaf_of_face_[node.face - first_face] = task.node;
      continue;
    }
    Box3 bounds;
    for (std::size_t i = task.first; i < task.first + task.count; ++i) bounds.extend(centroid[order[i] - first_face]);
    int axis = 0;
    bounds.sizes().maxCoeff(&axis);
    const auto begin = order.begin() + static_cast<std::ptrdiff_t>(task.first);
    const auto end = begin + static_cast<std::ptrdiff_t>(task.count);
    const auto middle = begin + static_cast<std::ptrdiff_t>(task.count / 2);
    // Ties broken by face id, so the tree depends only on the input.
    std::nth_element(begin, middle, end, [&](FaceId a, FaceId b) {
      const double ca = centroid[a - first_face][axis], cb = centroid[b - first_face][axis];
      return ca != cb ? ca < cb : a < b;
    });
    const auto left = static_cast<std::int32_t>(nodes_.size());
    nodes_[static_cast<std::size_t>(task.node)].left = left;
    nodes_[static_cast<std::size_t>(task.node)].right = left + 1;
    nodes_.push_back({});
    nodes_.push_back({});
    top_down.push_back(task.node);
    tasks.push_back({left, task.first, task.count / 2, task.depth + 1});
    tasks.push_back({left + 1, task.first + task.count / 2, task.count - task.count / 2, task.depth + 1});
  }
  bottom_up_.assign(top_down.rbegin(), top_down.rend());
  for (Node& node : nodes_) {
    if (node.is_leaf()) node.max_face = node.face;
  }
  for (std::int32_t n : bottom_up_) {
    Node& node = nodes_[static_cast<std::size_t>(n)];
    node.max_face = std::max(nodes_[static_cast<std::size_t>(node.left)].max_face, nodes_[static_cast<std::size_t>(node.right)].max_face);
  }
  parent_.assign(nodes_.size(), -1);
  for (std::int32_t n : top_down) {
    parent_[static_cast<std::size_t>(nodes_[static_cast<std::size_t>(n)].left)] = n;
    parent_[static_cast<std::size_t>(nodes_[static_cast<std::size_t>(n)].right)] = n;
  }
}

void TriangleBvh::enlarge_leaf(FaceId f, const Box3& box) {
  for (std::int32_t n = leaf_of(f); n >= 0; n = parent_[static_cast<std::size_t>(n)]) {
    Box3& node_box = nodes_[static_cast<std::size_t>(n)].box;
    if (node_box.contains(box)) break;  // ancestors hold it already
    node_box.extend(box);
  }
}

template <class Inflation>
void TriangleBvh::refit_with(const MeshTopology& topology, std::span<const Vec3> x0, std::span<const Vec3> x1, Inflation inflation) {
  tbb::parallel_for(std::size_t{0}, nodes_.size(), [&](std::size_t n) {
    Node& node = nodes_[n];
    if (!node.is_leaf()) return;
    node.box = swept_face_box(topology.face(node.face), x0, x1, inflation(node.face));
  });
  for (std::int32_t n : bottom_up_) {
    Node& node = nodes_[static_cast<std::size_t>(n)];
    node.box = nodes_[static_cast<std::size_t>(node.left)].box.merged(nodes_[static_cast<std::size_t>(node.right)].box);
  }
}

void TriangleBvh::refit(const MeshTopology& topology, std::span<const Vec3> x0, std::span<const Vec3> x1, double inflation) {
  refit_with(topology, x0, x1, [inflation](FaceId) { return inflation; });
}

void TriangleBvh::refit(const MeshTopology& topology, std::span<const Vec3> x0, std::span<const Vec3> x1, std::span<const double> inflation) {
  refit_with(topology, x0, x1, [&](FaceId f) { return inflation[f - first_face_]; });
}

namespace {

using Sink = std::vector<TrianglePair>;

/// A unit of traversal work: one node against itself (self) or two nodes against each other.
struct Task {
  bool self;
  std::int32_t a, b;
};

struct Traversal {
  const TriangleBvh& ta;
  const TriangleBvh& tb;
  /// Translations swept over b's boxes (zero for self traversal).
  Box3 b_offset{Vec3::Zero(), Vec3::Zero()};

  Box3 shifted(const Box3& box) const { return {box.min() + b_offset.min(), box.max() + b_offset.max()}; }

  const TriangleBvh::Node& node_a(std::int32_t i) const { return ta.nodes()[static_cast<std::size_t>(i)]; }
  const TriangleBvh::Node& node_b(std::int32_t i) const { return tb.nodes()[static_cast<std::size_t>(i)]; }

  /// Replaces a task by the tasks one level down (appended to `out`); false for a leaf pair (nothing to split).
  bool expand(const Task& task, std::vector<Task>& out) const {
    if (task.self) {
      const auto& n = node_a(task.a);
      if (n.is_leaf()) return true;  // a single face pairs with nothing
      out.push_back({true, n.left, n.left});
      out.push_back({true, n.right, n.right});
      out.push_back({false, n.left, n.right});
      return true;
    }
    const auto& na = node_a(task.a);
    const auto& nb = task_is_same_tree_ ? node_a(task.b) : node_b(task.b);
    if (!boxes_overlap(na.box, task_is_same_tree_ ? nb.box : shifted(nb.box))) return true;
    if (na.is_leaf() && nb.is_leaf()) return false;
    const bool descend_a = !na.is_leaf() && (nb.is_leaf() || na.box.volume() >= nb.box.volume());
    if (descend_a) {
      out.push_back({false, na.left, task.b});
      out.push_back({false, na.right, task.b});
    } else {
      out.push_back({false, task.a, nb.left});
      out.push_back({false, task.a, nb.right});
    }
    return true;
  }

  void run(const Task& task, Sink& sink) const {
    std::vector<Task> stack{task}, next;
    while (!stack.empty()) {
      const Task current = stack.back();
      stack.pop_back();
      next.clear();
      if (expand(current, next)) {
        stack.insert(stack.end(), next.begin(), next.end());
        continue;
      }
      const FaceId fa = node_a(current.a).face;
      const FaceId fb = (task_is_same_tree_ ? node_a(current.b) : node_b(current.b)).face;
      sink.emplace_back(std::min(fa, fb), std::max(fa, fb));
    }
  }

  bool task_is_same_tree_ = false;
};

std::vector<TrianglePair> traverse(const Traversal& traversal, Task root) {
  // Expand the top levels serially into a front of independent tasks, then run the front in parallel.
  std::vector<Task> front{root}, next;
  Sink leaf_pairs;
  for (int level = 0; level < 24 && !front.empty() && front.size() < 512; ++level) {
    next.clear();
    for (const Task& task : front) {
      std::vector<Task> children;
      if (traversal.expand(task, children)) {
        next.insert(next.end(), children.begin(), children.end());
      } else {
        traversal.run(task, leaf_pairs);
      }
    }
    front.swap(next);
  }
  tbb::enumerable_thread_specific<Sink> sinks;
  tbb::parallel_for(std::size_t{0}, front.size(), [&](std::size_t i) { traversal.run(front[i], sinks.local()); });
  for (const Sink& sink : sinks) leaf_pairs.insert(leaf_pairs.end(), sink.begin(), sink.end());
  tbb::parallel_sort(leaf_pairs.begin(), leaf_pairs.end());
  return leaf_pairs;
}

}  // namespace

std::vector<TrianglePair> self_overlaps(const TriangleBvh& tree) {
  if (tree.empty()) return {};
  // A depth-first walk that pushes both children holds at most one pending sibling per level, plus the node in
  // hand: depth + 1 entries. The median split's depth is ceil(log2 faces), at most 31 for int32 node ids.
  constexpr int kStackSize = 64;
  if (tree.depth() + 1 > kStackSize) throw std::logic_error("self_overlaps: a tree deeper than its traversal stack");
  // Boxes hold their children (refit merges them, enlarge_leaf grows the ancestors), which the pruning from the
  // root needs; frames are finite (their readers refuse NaN and infinity), so no NaN box breaks that.
  constexpr std::size_t kChunk = 256;  // faces per task: lists of a few thousand pairs, enough tasks for 16 threads
  const auto& nodes = tree.nodes();
  const std::size_t faces = tree.face_count();
  const std::size_t chunks = (faces + kChunk - 1) / kChunk;
  std::vector<Sink> lists(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
    Sink& list = lists[chunk];
    const std::size_t end = std::min(faces, (chunk + 1) * kChunk);
    for (std::size_t i = chunk * kChunk; i < end; ++i) {
      const FaceId a = tree.first_face() + static_cast<FaceId>(i);
      const Box3& box = nodes[static_cast<std::size_t>(tree.leaf_of(a))].box;
      const std::size_t first = list.size();
      std::int32_t stack[kStackSize];
      int size = 0;
      stack[size++] = 0;
      while (size > 0) {
        const TriangleBvh::Node& node = nodes[static_cast<std::size_t>(stack[--size])];
        // Each pair once, from its smaller face: subtrees with no larger face are the other faces' to find.
        if (node.max_face <= a || !boxes_overlap(node.box, box)) continue;
        if (node.is_leaf()) {
          list.emplace_back(a, node.face);
        } else {
          stack[size++] = node.right;
          stack[size++] = node.left;
        }
      }
      std::sort(list.begin() + static_cast<std::ptrdiff_t>(first), list.end());
    }
  });
  std::vector<std::size_t> offsets(chunks + 1, 0);
  for (std::size_t c = 0; c < chunks; ++c) offsets[c + 1] = offsets[c] + lists[c].size();
  std::vector<TrianglePair> pairs(offsets[chunks]);
  tbb::parallel_for(std::size_t{0}, chunks,
                    [&](std::size_t c) { std::copy(lists[c].begin(), lists[c].end(), pairs.begin() + static_cast<std::ptrdiff_t>(offsets[c])); });
  return pairs;
}

std::vector<TrianglePair> self_overlaps_tree_pairs(const TriangleBvh& tree) {
  if (tree.empty()) return {};
  Traversal traversal{tree, tree};
  traversal.task_is_same_tree_ = true;
  return traverse(traversal, {true, 0, 0});
}

std::vector<TrianglePair> pair_overlaps(const TriangleBvh& a, const TriangleBvh& b, const Box3& b_offset) {
  if (a.empty() || b.empty()) return {};
  return traverse(Traversal{a, b, b_offset}, {false, 0, 0});
}

std::vector<TrianglePair> subset_overlaps(std::span<const FaceId> subset, std::span<const Box3> subset_boxes, const TriangleBvh& tree) {
  if (tree.empty() || subset.empty()) return {};
  tbb::enumerable_thread_specific<Sink> sinks;
  tbb::parallel_for(std::size_t{0}, subset.size(), [&](std::size_t i) {
    Sink& sink = sinks.local();
    std::vector<std::int32_t> stack{0};
    while (!stack.empty()) {
      const auto& node = tree.nodes()[static_cast<std::size_t>(stack.back())];
      stack.pop_back();
      if (!boxes_overlap(node.box, subset_boxes[i])) continue;
      if (!node.is_leaf()) {
        stack.push_back(node.left);
        stack.push_back(node.right);
      } else if (node.face != subset[i]) {
        sink.emplace_back(std::min(node.face, subset[i]), std::max(node.face, subset[i]));
      }
    }
  });
  Sink pairs;
  for (const Sink& sink : sinks) pairs.insert(pairs.end(), sink.begin(), sink.end());
  tbb::parallel_sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

}  // namespace ccd::bvh
