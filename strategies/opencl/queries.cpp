// A step's queries: which faces are walked against which trees, and, for a step on several devices, their order
// dealt into ranges of equal work (full_opencl.cpp hands the ranges out).
#include "strategies/opencl/pipeline.hpp"

#include <algorithm>

namespace ccd::opencl {

namespace {

/// Queries dealt to the ranges of a step on several devices go in blocks of this many consecutive ones: a step's
/// cost is not spread evenly over its queries (faces in mesh order, so the contact-rich part of a cloth is a run
/// of them), and ranges cut in query order cost unevenly: the 1M-triangle ball's step on 4 GPUs waited 16 ms a device
/// for the slowest (reports/gpus). Dealt round-robin in blocks, each range holds every part of the mesh alike;
/// within a block the queries stay neighbours, so a warp's traversals stay alike (32 on NVIDIA, 64 on AMD: a block
/// holds many).
constexpr std::size_t kDealtBlock = 1024;
/// Blocks smaller than kDealtBlock where a range would get fewer than this many (a small scene's queries are spread
/// over every range too).
constexpr std::size_t kDealtBlocksPerRange = 8;

template <class T>
void permute(std::vector<T>& values, const std::vector<std::size_t>& order) {
  std::vector<T> permuted(values.size());
  for (std::size_t k = 0; k < order.size(); ++k) permuted[k] = values[order[k]];
  values = std::move(permuted);
}

}  // namespace

std::pair<std::vector<std::size_t>, std::vector<std::size_t>> deal_into_ranges(std::size_t count, std::size_t ranges) {
  std::vector<std::size_t> order, starts{0};
  order.reserve(count);
  const std::size_t size = std::clamp<std::size_t>(count / (ranges * kDealtBlocksPerRange), 1, kDealtBlock);
  const std::size_t blocks = (count + size - 1) / size;
  for (std::size_t r = 0; r < ranges; ++r) {
    for (std::size_t block = r; block < blocks; block += ranges) {
      for (std::size_t i = block * size; i < std::min(count, (block + 1) * size); ++i) order.push_back(i);
    }
    starts.push_back(order.size());
  }
  return {std::move(order), std::move(starts)};
}

void DevicePipeline::make_queries(Queries& queries, bool self, bool pairs, bool offsets, std::size_t ranges) {
  const Scene& scene = *scene_;
  std::vector<cl_uint> q_leaf, q_face;
  std::vector<cl_int> q_root, q_offset;
  std::vector<cl_uchar> q_mode;
  // mode: 0 pair, 1 self, 2 pair with the query's box swept by the offset, 3 pair with the tree's boxes swept.
  auto add = [&](ObjectId from, ObjectId into, cl_uchar mode, cl_int offset) {
    const SceneObject& object = scene.object(from);
    if (roots_[into] < 0 || roots_[from] < 0) return;
    for (FaceId f = object.first_face; f < object.first_face + object.num_faces; ++f) {
      q_leaf.push_back(leaf_node_[f]);
      q_face.push_back(f);
      q_root.push_back(roots_[into]);
      q_mode.push_back(mode);
      q_offset.push_back(offset);
    }
  };
  if (self) {
    for (ObjectId id = 0; id < scene.objects().size(); ++id) {
      if (scene.object(id).self_collision) add(id, id, 1, -1);
    }
  }
  if (pairs) {
    const auto& collidable = scene.collidable_pairs();
    for (std::size_t i = 0; i < collidable.size(); ++i) {
      const auto [a, b] = collidable[i];
      const cl_int index = offsets ? static_cast<cl_int>(i) : -1;
      if (scene.object(a).num_faces >= scene.object(b).num_faces) {
        add(a, b, offsets ? 3 : 0, index);  // a's faces against b's tree: b's boxes are swept
      } else {
        add(b, a, offsets ? 2 : 0, index);  // b's faces against a's tree: the query (b's) box is swept
      }
    }
  }
  queries.count = q_leaf.size();
  queries.range_starts = {0, queries.count};
  if (ranges > 1) {
    // (Any order gives the same answers: each query's pairs are its own, and a step's set is put in order.)
    auto [order, starts] = deal_into_ranges(queries.count, ranges);
    permute(q_leaf, order);
    permute(q_face, order);
    permute(q_root, order);
    permute(q_mode, order);
    permute(q_offset, order);
    queries.range_starts = std::move(starts);
  }
  upload(*context_, queries.leaf, q_leaf.data(), q_leaf.size());
  upload(*context_, queries.face, q_face.data(), q_face.size());
  upload(*context_, queries.root, q_root.data(), q_root.size());
  upload(*context_, queries.mode, q_mode.data(), q_mode.size());
  upload(*context_, queries.offset_index, q_offset.data(), q_offset.size());
  context_->finish();
}

}  // namespace ccd::opencl
