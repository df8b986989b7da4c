// Training a vocabulary tree: hierarchical k-medians, level by level, then IDF word weights.
//
// Determinism: every node draws from its own generator, seeded from the training seed and the node's
// path (child index at every level); threads only split work whose results are integer counts or
// per-descriptor assignments, so the tree is the same for any thread count.
#include "components/core/place/vocabulary_training.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <thread>

namespace heslam {
namespace {

using Members = std::vector<std::uint32_t>;  // indices into the clustered descriptor array

constexpr int kDescriptorBits = 256;

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

std::uint64_t child_seed(std::uint64_t parent_seed, std::size_t child_index) {
  return splitmix64(parent_seed ^ splitmix64(child_index + 1));
}

// Runs fn(begin, end, worker) over [0, count) split into `threads` contiguous ranges.
template <typename Fn>
void parallel_ranges(std::size_t count, int threads, Fn&& fn) {
  const std::size_t workers = std::max<std::size_t>(1, std::min<std::size_t>(threads, count));
  if (workers == 1) {
    fn(std::size_t{0}, count, std::size_t{0});
    return;
  }
  std::vector<std::thread> pool;
  for (std::size_t w = 0; w < workers; ++w) {
    pool.emplace_back([&, w] { fn(count * w / workers, count * (w + 1) / workers, w); });
  }
  for (auto& t : pool) t.join();
}

// Runs fn(i) for i in [0, count) on `threads` threads, items handed out one at a time.
template <typename Fn>
void parallel_items(std::size_t count, int threads, Fn&& fn) {
  const int workers = static_cast<int>(std::max<std::size_t>(1, std::min<std::size_t>(threads, count)));
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i = next++; i < count; i = next++) fn(i);
  };
  if (workers == 1) {
    work();
    return;
  }
  std::vector<std::thread> pool;
  for (int w = 0; w < workers; ++w) pool.emplace_back(work);
  for (auto& t : pool) t.join();
}

struct Child {
  Descriptor centre{};
  Members members;
  bool leaf = false;
};

class NodeClusterer {
 public:
  NodeClusterer(const std::vector<Descriptor>& descriptors, int k, int max_iterations)
      : descriptors_(descriptors), k_(k), max_iterations_(max_iterations) {}

  // The children of a node holding `members` at depth `depth` (root 0) of an L-level tree.
  std::vector<Child> split(const Members& members, int depth, int levels, std::uint64_t seed, int threads) const {
    std::vector<Child> children;
    if (members.size() <= static_cast<std::size_t>(k_)) {
      for (const std::uint32_t m : members) {
        const Descriptor& d = descriptors_[m];
        auto same = [&](const Child& c) { return c.centre == d; };
        auto it = std::find_if(children.begin(), children.end(), same);
        if (it == children.end())
          children.push_back({d, {m}, true});
        else
          it->members.push_back(m);
      }
      return children;
    }
    std::vector<Descriptor> centres = seed_centres(members, seed, threads);
    std::vector<std::uint8_t> assignment(members.size(), 0);
    assign(members, centres, assignment, threads);
    for (int iteration = 1; iteration < max_iterations_; ++iteration) {
      update_medians(members, assignment, centres, threads);
      if (!assign(members, centres, assignment, threads)) break;
    }
    children.resize(centres.size());
    for (std::size_t c = 0; c < centres.size(); ++c) children[c].centre = centres[c];
    for (std::size_t i = 0; i < members.size(); ++i) children[assignment[i]].members.push_back(members[i]);
    std::erase_if(children, [](const Child& c) { return c.members.empty(); });
    for (Child& child : children) {
      const Descriptor& first = descriptors_[child.members.front()];
      const bool all_equal = std::all_of(child.members.begin(), child.members.end(),
                                         [&](std::uint32_t m) { return descriptors_[m] == first; });
      child.leaf = depth + 1 >= levels || all_equal;
    }
    return children;
  }

 private:
  // k-means++: the first centre uniformly, each next one with probability proportional to the
  // squared Hamming distance to the nearest centre so far. Stops early when every descriptor
  // coincides with a centre (fewer than k distinct descriptors).
  std::vector<Descriptor> seed_centres(const Members& members, std::uint64_t seed, int threads) const {
    std::mt19937_64 rng(seed);
    std::vector<Descriptor> centres;
    centres.push_back(descriptors_[members[rng() % members.size()]]);
    std::vector<std::uint32_t> nearest_sq(members.size(), std::numeric_limits<std::uint32_t>::max());
    while (centres.size() < static_cast<std::size_t>(k_)) {
      const Descriptor& latest = centres.back();
      parallel_ranges(members.size(), threads, [&](std::size_t begin, std::size_t end, std::size_t) {
        for (std::size_t i = begin; i < end; ++i) {
          const auto d = static_cast<std::uint32_t>(hamming_distance(descriptors_[members[i]], latest));
          nearest_sq[i] = std::min(nearest_sq[i], d * d);
        }
      });
      std::uint64_t total = 0;
      for (const std::uint32_t d2 : nearest_sq) total += d2;
      if (total == 0) break;
      const std::uint64_t target = rng() % total;
      std::uint64_t cumulative = 0;
      std::size_t pick = 0;
      for (; pick < members.size(); ++pick) {
        cumulative += nearest_sq[pick];
        if (cumulative > target) break;
      }
      centres.push_back(descriptors_[members[pick]]);
    }
    return centres;
  }

  // Nearest centre per member (first on ties); returns whether any assignment changed.
  bool assign(const Members& members, const std::vector<Descriptor>& centres, std::vector<std::uint8_t>& assignment,
              int threads) const {
    std::atomic<bool> changed{false};
    parallel_ranges(members.size(), threads, [&](std::size_t begin, std::size_t end, std::size_t) {
      bool local_changed = false;
      for (std::size_t i = begin; i < end; ++i) {
        const Descriptor& d = descriptors_[members[i]];
        std::uint8_t best = 0;
        int best_distance = hamming_distance(d, centres[0]);
        for (std::size_t c = 1; c < centres.size(); ++c) {
          const int distance = hamming_distance(d, centres[c]);
          if (distance < best_distance) {
            best_distance = distance;
            best = static_cast<std::uint8_t>(c);
          }
        }
        if (assignment[i] != best) {
          assignment[i] = best;
          local_changed = true;
        }
      }
      if (local_changed) changed = true;
    });
    return changed;
  }

  // Per cluster and bit, the majority of its members' bits (ties give 0); an emptied cluster keeps
  // its centre.
  void update_medians(const Members& members, const std::vector<std::uint8_t>& assignment,
                      std::vector<Descriptor>& centres, int threads) const {
    const std::size_t k = centres.size();
    const std::size_t workers = std::max(1, threads);
    std::vector<std::vector<std::uint32_t>> bit_counts(workers, std::vector<std::uint32_t>(k * kDescriptorBits, 0));
    std::vector<std::vector<std::uint32_t>> sizes(workers, std::vector<std::uint32_t>(k, 0));
    parallel_ranges(members.size(), threads, [&](std::size_t begin, std::size_t end, std::size_t worker) {
      for (std::size_t i = begin; i < end; ++i) {
        const Descriptor& d = descriptors_[members[i]];
        std::uint32_t* counts = bit_counts[worker].data() + assignment[i] * kDescriptorBits;
        ++sizes[worker][assignment[i]];
        for (int bit = 0; bit < kDescriptorBits; ++bit) counts[bit] += (d[bit >> 3] >> (bit & 7)) & 1u;
      }
    });
    for (std::size_t c = 0; c < k; ++c) {
      std::uint32_t size = 0;
      for (std::size_t w = 0; w < workers; ++w) size += sizes[w][c];
      if (size == 0) continue;
      Descriptor median{};
      for (int bit = 0; bit < kDescriptorBits; ++bit) {
        std::uint32_t ones = 0;
        for (std::size_t w = 0; w < workers; ++w) ones += bit_counts[w][c * kDescriptorBits + bit];
        if (2 * ones > size) median[bit >> 3] |= static_cast<std::uint8_t>(1u << (bit & 7));
      }
      centres[c] = median;
    }
  }

  const std::vector<Descriptor>& descriptors_;
  int k_;
  int max_iterations_;
};

void check_options(const std::vector<std::vector<Descriptor>>& images, const VocabularyTrainingOptions& options) {
  if (options.branching < 2 || options.branching > 255) {
    throw std::invalid_argument("train_vocabulary: branching k must be in 2..255, got " +
                                std::to_string(options.branching));
  }
  if (options.levels < 1 || options.levels > 32) {
    throw std::invalid_argument("train_vocabulary: levels L must be in 1..32, got " + std::to_string(options.levels));
  }
  if (options.threads < 1)
    throw std::invalid_argument("train_vocabulary: threads must be >= 1, got " + std::to_string(options.threads));
  if (options.max_iterations < 1) {
    throw std::invalid_argument("train_vocabulary: max_iterations must be >= 1, got " +
                                std::to_string(options.max_iterations));
  }
  const bool any = std::any_of(images.begin(), images.end(), [](const auto& image) { return !image.empty(); });
  if (!any) throw std::invalid_argument("train_vocabulary: no descriptors to train on");
}

// The descriptors the tree is clustered from: all, or a uniform sample without replacement, in
// their original order.
std::vector<Descriptor> clustering_set(const std::vector<std::vector<Descriptor>>& images,
                                       const VocabularyTrainingOptions& options) {
  std::vector<Descriptor> all;
  for (const auto& image : images) all.insert(all.end(), image.begin(), image.end());
  if (options.max_cluster_descriptors == 0 || all.size() <= options.max_cluster_descriptors) return all;
  std::vector<std::uint32_t> index(all.size());
  for (std::size_t i = 0; i < index.size(); ++i) index[i] = static_cast<std::uint32_t>(i);
  std::mt19937_64 rng(splitmix64(options.seed ^ 0x5a4d504c45ull));
  const std::size_t wanted = options.max_cluster_descriptors;
  for (std::size_t i = 0; i < wanted; ++i) std::swap(index[i], index[i + rng() % (index.size() - i)]);
  index.resize(wanted);
  std::sort(index.begin(), index.end());
  std::vector<Descriptor> sample;
  sample.reserve(wanted);
  for (const std::uint32_t i : index) sample.push_back(all[i]);
  return sample;
}

struct PendingNode {
  NodeId id = 0;
  int depth = 0;
  std::uint64_t seed = 0;
  Members members;
};

}  // namespace

Vocabulary train_vocabulary(const std::vector<std::vector<Descriptor>>& images,
                            const VocabularyTrainingOptions& options) {
  check_options(images, options);
  const auto start = std::chrono::steady_clock::now();
  auto report = [&](const std::string& line) {
    if (!options.progress) return;
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char stamp[32];
    std::snprintf(stamp, sizeof(stamp), "[%.1f s] ", s);
    options.progress(stamp + line);
  };

  const std::vector<Descriptor> descriptors = clustering_set(images, options);
  report("clustering " + std::to_string(descriptors.size()) +
         " descriptors into k = " + std::to_string(options.branching) + ", L = " + std::to_string(options.levels));
  const NodeClusterer clusterer(descriptors, options.branching, options.max_iterations);

  std::vector<Vocabulary::NodeRecord> nodes;  // node id i + 1, breadth first
  std::vector<PendingNode> level(1);
  level[0].seed = splitmix64(options.seed);
  level[0].members.resize(descriptors.size());
  for (std::size_t i = 0; i < descriptors.size(); ++i) level[0].members[i] = static_cast<std::uint32_t>(i);
  std::size_t words = 0;
  for (int depth = 0; !level.empty(); ++depth) {
    std::vector<std::vector<Child>> children(level.size());
    // A level with fewer nodes than threads (the root's) clusters each node with all threads.
    const bool whole_team_per_node = level.size() < static_cast<std::size_t>(options.threads);
    if (whole_team_per_node) {
      for (std::size_t i = 0; i < level.size(); ++i) {
        children[i] = clusterer.split(level[i].members, depth, options.levels, level[i].seed, options.threads);
      }
    } else {
      parallel_items(level.size(), options.threads, [&](std::size_t i) {
        children[i] = clusterer.split(level[i].members, depth, options.levels, level[i].seed, 1);
      });
    }
    std::vector<PendingNode> next;
    for (std::size_t i = 0; i < level.size(); ++i) {
      level[i].members = Members{};  // handed down to the children
      for (std::size_t c = 0; c < children[i].size(); ++c) {
        Child& child = children[i][c];
        nodes.push_back({level[i].id, child.leaf, child.centre, child.leaf ? 1.f : 0.f});
        const NodeId id = static_cast<NodeId>(nodes.size());
        if (child.leaf) {
          ++words;
        } else {
          next.push_back({id, depth + 1, child_seed(level[i].seed, c), std::move(child.members)});
        }
      }
    }
    report("level " + std::to_string(depth + 1) + "/" + std::to_string(options.levels) + ": " +
           std::to_string(nodes.size()) + " nodes, " + std::to_string(words) + " words, " +
           std::to_string(next.size()) + " nodes to split");
    level = std::move(next);
  }

  // Word weights: in how many training images each word occurs.
  const Vocabulary tree(options.branching, options.levels, options.scoring, options.weighting, nodes);
  const bool uses_idf = options.weighting == BowWeighting::kTfIdf || options.weighting == BowWeighting::kIdf;
  if (uses_idf) {
    const std::size_t workers = static_cast<std::size_t>(options.threads);
    std::vector<std::vector<std::uint32_t>> images_with_word(workers, std::vector<std::uint32_t>(tree.word_count(), 0));
    parallel_ranges(images.size(), options.threads, [&](std::size_t begin, std::size_t end, std::size_t worker) {
      std::vector<WordId> image_words;
      for (std::size_t i = begin; i < end; ++i) {
        image_words.clear();
        for (const Descriptor& d : images[i]) image_words.push_back(tree.word_of(d));
        std::sort(image_words.begin(), image_words.end());
        image_words.erase(std::unique(image_words.begin(), image_words.end()), image_words.end());
        for (const WordId w : image_words) ++images_with_word[worker][w];
      }
    });
    const double image_count = static_cast<double>(images.size());
    for (WordId w = 0; w < tree.word_count(); ++w) {
      std::uint32_t count = 0;
      for (const auto& counts : images_with_word) count += counts[w];
      nodes[tree.node_of_word(w) - 1].weight =
          static_cast<float>(std::log(image_count / std::max<std::uint32_t>(count, 1)));
    }
    report("weights from " + std::to_string(images.size()) + " images");
  }
  return Vocabulary(options.branching, options.levels, options.scoring, options.weighting, nodes);
}

}  // namespace heslam
