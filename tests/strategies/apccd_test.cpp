// APCCD: never loses a candidate, under every knob, on any thread count.

#include "datasets/procedural_scenes.hpp"
#include "datasets/scene_file.hpp"
#include "reference/step_truth.hpp"
#include "strategies/apccd/session.hpp"
#include "strategies/bvh/bvh.hpp"
#include "strategies/registry.hpp"
#include "tests/support/strategy_runs.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <iostream>

namespace ccd::strategies {
namespace {

double extra(const StepResult& result, const std::string& name) {
  for (const auto& [key, value] : result.counters.extra) {
    if (key == name) return value;
  }
  return -1;
}

// One self-colliding object made of two layers: a sheet barely moving (so the session goes on) and a second
// sheet 1 above it. In step 3, inside a session, one vertex of the upper layer jumps down through the lower one.
// It moves far relative to its object, so it is dangling, and only the partial traversal can bring the new
// pairs into the pending list (they are self pairs: no object-pair traversal sees them).
TEST(Apccd, PartialTraversalFindsThePairOfAVertexThatJumpsFarDuringASession) {
  const std::size_t n = 5;
  std::vector<Face> faces = testing::grid_faces(n);
  for (const Face& f : testing::grid_faces(n)) {
    faces.push_back({f[0] + static_cast<VertexId>(n * n), f[1] + static_cast<VertexId>(n * n), f[2] + static_cast<VertexId>(n * n)});
  }
  const Scene scene({{"layers", ObjectKind::deformable, true, 2 * n * n, faces}}, {}, 0.0);
  const std::size_t jumper = n * n + 2 * n + 2;  // the middle vertex of the upper layer
  std::vector<std::vector<Vec3>> frames;
  for (int k = 0; k < 8; ++k) {
    std::vector<Vec3> x = testing::grid_positions(n, 1e-4 * k);
    const std::vector<Vec3> upper = testing::grid_positions(n, 1.0);
    x.insert(x.end(), upper.begin(), upper.end());
    if (k >= 4) x[jumper].z() = -0.5;  // the jump: step 3 goes from frame 3 to frame 4
    frames.push_back(x);
  }
  auto strategy = make_strategy("apccd:nf_min=8:nf_max=8");
  strategy->init(scene, frames[0]);
  for (std::size_t k = 0; k + 1 < frames.size(); ++k) {
    const StepResult result = strategy->step({&scene, k, frames[k], frames[k + 1]}, false);
    const auto truth = reference::compute_step_truth(scene, frames[k], frames[k + 1], {0.0, false, {}});
    EXPECT_TRUE(set_difference(truth.collisions, result.collisions).empty()) << "step " << k << " missed a collision";
    if (k == 3) {
      EXPECT_GT(truth.collisions.size(), 0u) << "the jump must collide for this test to mean anything";
      EXPECT_EQ(extra(result, "session_start"), 0.0) << "the jump must happen inside a session";
      EXPECT_GT(extra(result, "dangling_vertices"), 0.0);
    }
  }
}

// One test per built-in scene, so that ctest spreads them over the cores.
class ApccdOnScene : public ::testing::TestWithParam<std::string> {};

TEST_P(ApccdOnScene, MissesNothingUnderEveryKnobAndThreadCount) {
  testing::TempDir dir;
  const testing::LoadedScene loaded = testing::small_scene(GetParam(), dir);
  const auto& frames = loaded.frames;
  for (double thickness : {0.0, loaded.sequence.scene().thickness()}) {
    const Scene scene = loaded.sequence.scene().with_thickness(thickness);
    std::vector<CollisionSet> truth;
    std::size_t colliding = 0;
    for (std::size_t k = 0; k + 1 < frames.size(); ++k) {
      truth.push_back(reference::compute_step_truth(scene, frames[k], frames[k + 1], {thickness, false, {}}).collisions);
      colliding += truth.back().size();
    }
    EXPECT_GT(colliding, 0u) << GetParam() << ", δ = " << thickness << ": nothing to miss, the test would prove nothing";
    // Every knob, at least once: defaults; no skipping, no front end, history on; no inflation at all (every
    // motion dangles) with the box filter alone as front end; object pairs from the session's trees with persistent history; long sessions (nf 2..16, no
    // inflation cap, many dangling vertices and a long pending list allowed before a session ends).
    for (const char* spec :
         {"apccd", "apccd:skip=off:heuristic=off:history=on", "apccd:local=0:global=0:heuristic=boxes",
          "apccd:object_pairs=session:history=persistent", "apccd:nf_min=2:nf_max=16:inflation_max=1e9:dangling_max=0.5:pending_max=1e9"}) {
      SCOPED_TRACE(GetParam() + ", δ = " + std::to_string(thickness) + ", " + spec);
      const auto two = testing::run_all_steps(spec, scene, frames, 2);
      // One thread against two for the default and for the longest sessions (where most state is carried from
      // step to step); once is enough for the other knobs (this test runs under ASan in CI too).
      const std::string name = spec;
      const bool threads_compared = name == "apccd" || name.find("nf_max=16") != std::string::npos;
      const auto one = threads_compared ? testing::run_all_steps(spec, scene, frames, 1) : two;
      for (std::size_t k = 0; k < truth.size(); ++k) {
        ASSERT_TRUE(set_difference(truth[k], two[k]).empty()) << "step " << k << " missed " << set_difference(truth[k], two[k]).size();
        ASSERT_TRUE(one[k].same_pairs(two[k])) << "step " << k << ": 1 and 2 threads differ";
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(BuiltInScenes, ApccdOnScene, ::testing::ValuesIn(testing::procedural_scene_names()), testing::param_name);
INSTANTIATE_TEST_SUITE_P(ShapeScenes, ApccdOnScene, ::testing::ValuesIn(testing::shape_scene_names()), testing::param_name);

// With the box filter alone as its front end, apccd admits the candidates its sessions, partial traversals and
// object pairs found whose fresh swept boxes overlap. It finds self pairs in each object's frame (relative to the
// object's centroid), full in the world: a translation of a whole object during the step can make world boxes overlap
// where relative boxes do not, and such a pair cannot come within δ (its distance at every instant is that of its
// relative positions). So apccd tests a subset of full's elementary pairs and answers each as full does (the same
// narrow phase on the same rows, TOIs included), and every pair full tests that apccd does not is a self pair whose
// primitives' boxes relative to their object's centroid, widened by δ/2, are apart, and is not in the exact truth.
// A pair the sessions, partial traversals or object pairs lost breaks that (it fails when the partial traversal's
// pairs are dropped). On the fold (self contact inside sessions), the spinning ball (object pairs) and the drape
// (falling, then against a static table), both δ, with the default inflation and with none (every moving vertex
// dangles: the partial traversals find the rest).
TEST(Apccd, WithTheBoxFrontEndTestsFullsPairsLessThoseItsObjectFramesProveApart) {
  testing::TempDir dir;
  const auto tois = [](const CollisionSet& set) {
    std::vector<double> all;
    for (const auto& contact : set.vertex_face()) all.push_back(contact.toi);
    for (const auto& contact : set.edge_edge()) all.push_back(contact.toi);
    return all;
  };
  for (const char* name : {"fold", "spinning-ball", "drape"}) {
    const testing::LoadedScene loaded = testing::small_scene(name, dir);
    for (double thickness : {0.0, loaded.sequence.scene().thickness()}) {
      const Scene scene = loaded.sequence.scene().with_thickness(thickness);
      // Positions relative to their object's centroid, formed as apccd forms them (ApccdSession: each moving
      // object's centroid summed in vertex order; static objects stay in the world).
      const auto relative = [&](const std::vector<Vec3>& x) {
        std::vector<Vec3> r = x;
        for (ObjectId id = 0; id < scene.objects().size(); ++id) {
          const SceneObject& object = scene.object(id);
          if (object.kind == ObjectKind::static_object || object.num_vertices == 0) continue;
          Vec3 centroid = Vec3::Zero();
          for (std::size_t i = 0; i < object.num_vertices; ++i) centroid += x[object.first_vertex + i];
          centroid /= static_cast<double>(object.num_vertices);
          for (std::size_t i = 0; i < object.num_vertices; ++i) r[object.first_vertex + i] = x[object.first_vertex + i] - centroid;
        }
        return r;
      };
      for (const char* spec : {"apccd+cubic64:heuristic=boxes", "apccd+cubic64:heuristic=boxes:local=0:global=0"}) {
        auto full = make_strategy("full+cubic64");
        auto apccd = make_strategy(spec);
        full->init(scene, loaded.frames[0]);
        apccd->init(scene, loaded.frames[0]);
        double inside = 0, dangling = 0;
        std::size_t compared = 0, dropped = 0;
        for (std::size_t k = 0; k + 1 < loaded.frames.size(); ++k) {
          SCOPED_TRACE(std::string(name) + ", δ = " + std::to_string(thickness) + ", " + spec + ", step " + std::to_string(k));
          const StepView step{&scene, k, loaded.frames[k], loaded.frames[k + 1]};
          const StepResult expected = full->step(step, true);
          const StepResult result = apccd->step(step, true);
          EXPECT_EQ(extra(result, "distance_filtered"), 0.0) << "the distance heuristic ran";
          const CollisionSet truth = reference::compute_step_truth(scene, step.x0, step.x1, {thickness, false, {}}).collisions;
          const std::vector<Vec3> r0 = relative(loaded.frames[k]), r1 = relative(loaded.frames[k + 1]);
          const auto apart_in_object_frame = [&](std::initializer_list<VertexId> a, std::initializer_list<VertexId> b) {
            Box3 box_a, box_b;
            for (VertexId v : a) box_a.extend(r0[v]).extend(r1[v]);
            for (VertexId v : b) box_b.extend(r0[v]).extend(r1[v]);
            // Pairs across objects come from world-frame trees, as full's: none of them may be missing.
            const ObjectId object = scene.object_of_vertex(*a.begin());
            for (const auto& group : {a, b}) {
              for (VertexId v : group) {
                if (scene.object_of_vertex(v) != object) return false;
              }
            }
            return !boxes_overlap(bvh::widened(box_a, thickness / 2), bvh::widened(box_b, thickness / 2));
          };
          const TestedPairs& all = *expected.tested;
          const TestedPairs& some = *result.tested;
          ASSERT_TRUE(std::includes(all.vertex_face.begin(), all.vertex_face.end(), some.vertex_face.begin(), some.vertex_face.end()));
          ASSERT_TRUE(std::includes(all.edge_edge.begin(), all.edge_edge.end(), some.edge_edge.begin(), some.edge_edge.end()));
          std::vector<VertexFacePair> vertex_face;
          std::set_difference(all.vertex_face.begin(), all.vertex_face.end(), some.vertex_face.begin(), some.vertex_face.end(),
                              std::back_inserter(vertex_face));
          for (const VertexFacePair& p : vertex_face) {
            const Face& f = scene.topology().face(p.f);
            ASSERT_TRUE(apart_in_object_frame({p.v}, {f[0], f[1], f[2]})) << "vertex " << p.v << ", face " << p.f << " lost";
            ASSERT_FALSE(truth.contains(p));
          }
          std::vector<EdgeEdgePair> edge_edge;
          std::set_difference(all.edge_edge.begin(), all.edge_edge.end(), some.edge_edge.begin(), some.edge_edge.end(),
                              std::back_inserter(edge_edge));
          for (const EdgeEdgePair& p : edge_edge) {
            ASSERT_TRUE(apart_in_object_frame({p.a.v0, p.a.v1}, {p.b.v0, p.b.v1}))
                << "edges " << p.a.v0 << "-" << p.a.v1 << ", " << p.b.v0 << "-" << p.b.v1 << " lost";
            ASSERT_FALSE(truth.contains(p));
          }
          // full's answers on the pairs apccd tested are apccd's, TOIs included.
          CollisionSet restricted;
          for (const auto& contact : expected.collisions.vertex_face()) {
            if (std::binary_search(some.vertex_face.begin(), some.vertex_face.end(), contact.pair)) restricted.add(contact.pair, contact.toi);
          }
          for (const auto& contact : expected.collisions.edge_edge()) {
            if (std::binary_search(some.edge_edge.begin(), some.edge_edge.end(), contact.pair)) restricted.add(contact.pair, contact.toi);
          }
          restricted.normalize();
          ASSERT_TRUE(result.collisions.same_pairs(restricted));
          ASSERT_EQ(tois(result.collisions), tois(restricted)) << "the same pairs with other TOIs";
          inside += 1 - extra(result, "session_start");
          dangling += extra(result, "dangling_vertices");
          compared += some.vertex_face.size() + some.edge_edge.size();
          dropped += vertex_face.size() + edge_edge.size();
        }
        EXPECT_GT(inside, 0.0) << name << ", " << spec << ": no step inside a session";
        EXPECT_GT(compared, 0u) << name << ": nothing tested, nothing compared";
        if (std::string(spec).find("local=0") != std::string::npos) {
          EXPECT_GT(dangling, 0.0) << name << ": no partial traversal";
        }
        std::cout << name << ", δ = " << thickness << ", " << spec << ": " << compared << " pairs tested as full does, " << dropped
                  << " of full's proved apart in their object's frame\n";
      }
    }
  }
}

// The pairs a session start finds are not the whole story: on the fold, contacts begin inside sessions, where only
// the pending list and partial traversals can bring them to the back end.
TEST(Apccd, FindsContactsInsideSessionsNotOnlyAtTheirStarts) {
  testing::TempDir dir;
  const testing::LoadedScene loaded = testing::small_scene("fold", dir);
  for (double thickness : {0.0, loaded.sequence.scene().thickness()}) {
    const Scene scene = loaded.sequence.scene().with_thickness(thickness);
    auto strategy = make_strategy("apccd");
    strategy->init(scene, loaded.frames[0]);
    std::size_t inside = 0;
    for (std::size_t k = 0; k + 1 < loaded.frames.size(); ++k) {
      const StepResult result = strategy->step({&scene, k, loaded.frames[k], loaded.frames[k + 1]}, false);
      const auto truth = reference::compute_step_truth(scene, loaded.frames[k], loaded.frames[k + 1], {thickness, false, {}});
      ASSERT_TRUE(set_difference(truth.collisions, result.collisions).empty()) << "step " << k;
      if (extra(result, "session_start") == 0.0) inside += truth.collisions.size();
    }
    EXPECT_GT(inside, 0u) << "δ = " << thickness << ": no contact inside a session";
  }
}

// History's two lifetimes: a vertex crosses a face while the front end did not test the pair (the step between).
// history=on forgot the pair's side when it went untested; the paper's persistent history still has it.
// Each rule that ends a session, driven through ApccdSession on one triangle (edge length 1): the step's reason is
// the rule that ended it, and the next session's length follows from it.
TEST(ApccdSession, EachSessionEndsByTheRuleThatEndedIt) {
  const std::vector<Vec3> rest = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const Scene scene({ObjectDescription{"sheet", ObjectKind::deformable, true, 3, {{0, 1, 2}}}}, {}, 1e-3);
  // Every vertex moves `motion` (relative to the others: the centroid is taken out by the caller, here none).
  auto moved = [&](double motion) {
    std::vector<Vec3> x = rest;
    x[0].x() -= motion;
    x[1].x() += motion;
    x[2].y() += motion;
    return x;
  };
  // Runs one session from its start, each step with `dangling` vertices and `pending` pairs per admissible one;
  // returns every step's reason up to the end and the next session's nf.
  auto session = [&](ApccdSession& s, double motion, std::size_t dangling, std::size_t pending) {
    std::vector<double> budget;
    s.start(rest, moved(motion), budget);
    std::vector<SessionEnd> ends;
    do {
      ends.push_back(s.advance(dangling, 1, pending));
    } while (ends.back() == SessionEnd::none && ends.size() < 100);
    return ends;
  };
  ApccdSettings settings;  // nf_max 8, inflation_max 0.5, dangling_max 0.05, pending_max 4
  const std::vector<SessionEnd> eight_frames = {SessionEnd::none, SessionEnd::none, SessionEnd::none, SessionEnd::none,
                                                SessionEnd::none, SessionEnd::none, SessionEnd::none, SessionEnd::nf_max};
  {
    ApccdSession s;
    s.init(settings, scene, rest);
    EXPECT_EQ(session(s, 1e-6, 0, 0), eight_frames) << "a still sheet runs nf_max frames";
    EXPECT_EQ(session(s, 1e-6, 3, 0), std::vector<SessionEnd>{SessionEnd::dangling}) << "every vertex dangles at once";
    EXPECT_EQ(s.nf(), 4);
    EXPECT_EQ(session(s, 1e-6, 0, 5), std::vector<SessionEnd>{SessionEnd::pending}) << "5 pending pairs per admissible one";
    EXPECT_EQ(s.nf(), 2);
    const std::vector<SessionEnd> two = {SessionEnd::none, SessionEnd::nf_adapted};
    EXPECT_EQ(session(s, 1e-6, 0, 0), two) << "nf halved twice, then doubled at the end of a quiet session";
    EXPECT_EQ(s.nf(), 4);
  }
  {
    // Motion 0.1 an edge per frame: a budget of about 0.1 to 0.2 per frame reaches inflation_max (0.5) in a few
    // frames, fewer than nf_max.
    ApccdSession s;
    s.init(settings, scene, rest);
    const std::vector<SessionEnd> capped = session(s, 0.1, 0, 0);
    ASSERT_GT(capped.size(), 1u);
    EXPECT_LT(capped.size(), 8u);
    EXPECT_EQ(capped.back(), SessionEnd::inflation_cap);
  }
  {
    settings.skip = false;
    ApccdSession s;
    s.init(settings, scene, rest);
    EXPECT_EQ(session(s, 1e-6, 0, 0), std::vector<SessionEnd>{SessionEnd::skip_off});
  }
  std::vector<std::pair<std::string, double>> counters;
  add_session_end_counters(SessionEnd::pending, counters);
  ASSERT_EQ(counters.size(), std::size(kSessionEnds));
  for (const auto& [name, value] : counters) EXPECT_EQ(value, name == "session_end_pending" ? 1.0 : 0.0) << name;
}

TEST(ProximityHistory, PersistentKeepsAPairTheFrontEndSkippedAndCatchesItsFlip) {
  const MeshTopology topology(4, {{0, 1, 2}});
  const VertexFacePair pair{3, 0};
  const std::vector<Vec3> above = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.25, 0.25, 0.5)};
  std::vector<Vec3> below = above;
  below[3].z() = -0.5;
  const TestedPairs tested{{pair}, {}};
  const TestedPairs untested{};
  for (const HistoryMode mode : {HistoryMode::step, HistoryMode::persistent}) {
    ProximityHistory history(mode);
    CollisionSet collisions;
    EXPECT_EQ(history.apply(topology, above, tested, collisions), 0u);
    EXPECT_EQ(history.apply(topology, below, untested, collisions), 0u);
    EXPECT_EQ(history.pairs(), mode == HistoryMode::persistent ? 1u : 0u);
    const std::size_t caught = history.apply(topology, below, tested, collisions);
    EXPECT_EQ(caught, mode == HistoryMode::persistent ? 1u : 0u) << (mode == HistoryMode::persistent ? "persistent" : "step");
    EXPECT_EQ(collisions.contains(pair), mode == HistoryMode::persistent);
  }
  EXPECT_NE(make_strategy("apccd:history=persistent")->name().find(":history=persistent"), std::string::npos);
  EXPECT_NE(make_strategy("apccd:history=on")->name().find(":history=on"), std::string::npos);
}

TEST(Apccd, KnobsAreParsedRecordedAndChecked) {
  const std::string name = make_strategy("apccd+cubic64:skip=off:nf_max=4:eta=1e-05")->name();
  EXPECT_NE(name.find("apccd+cubic64:eta=1e-05"), std::string::npos) << name;
  EXPECT_NE(name.find(":skip=off"), std::string::npos) << name;
  EXPECT_NE(name.find(":nf_max=4"), std::string::npos) << name;
  EXPECT_THROW(make_strategy("apccd:skip=maybe"), std::invalid_argument);
  EXPECT_THROW(make_strategy("apccd:nf_min=9:nf_max=4"), std::invalid_argument);
  EXPECT_THROW(make_strategy("apccd:nff=3"), std::invalid_argument);
  // apccd's own keys are apccd's, not the narrow phase's: `apccd:foo=1` used to be blamed on "conservative".
  const std::string unknown = testing::error_message<std::invalid_argument>([] { make_strategy("apccd:foo=1"); });
  EXPECT_NE(unknown.find("apccd+conservative has no parameter 'foo' (apccd's: skip, nf_min, nf_max"), std::string::npos) << unknown;
  // nf_max=2^31 used to wrap in the conversion to int and give a wrong message.
  const std::string huge = testing::error_message<std::invalid_argument>([] { make_strategy("apccd:nf_max=2147483648"); });
  EXPECT_NE(huge.find("apccd: nf_max=2147483648 must be an integer in [1, 1000]"), std::string::npos) << huge;
  for (const char* bad : {"apccd:nf_min=2.5", "apccd:local=-1", "apccd:global=1e7", "apccd:dangling_max=1.5", "apccd:pending_max=0.5",
                          "apccd:inflation_max=-1", "apccd:object_pairs=stale", "apccd:history=2", "apccd:history=forever"}) {
    EXPECT_THROW(make_strategy(bad), std::invalid_argument) << bad;
  }
}

}  // namespace
}  // namespace ccd::strategies
