// A small vocabulary with a known answer for place-recognition tests: a 2-level tree, `branching`
// random centres at level 1 and `branching` leaves under each (the centre with a few bits flipped),
// so word_descriptor(w) descends exactly to word w. All idf weights 1.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "../tracking/synthetic_scene.hpp"
#include "components/core/place/vocabulary.hpp"

namespace heslam::test {

class HandBuiltVocabulary {
 public:
  explicit HandBuiltVocabulary(int branching = 4, std::uint64_t seed = 7) {
    std::mt19937_64 rng(seed);
    std::vector<Vocabulary::NodeRecord> nodes;
    std::vector<Descriptor> centres;
    for (int c = 0; c < branching; ++c) {
      centres.push_back(random_descriptor(rng));
      nodes.push_back({0, false, centres.back(), 1.f});
    }
    for (int c = 0; c < branching; ++c) {
      for (int l = 0; l < branching; ++l) {
        Descriptor leaf = centres[static_cast<std::size_t>(c)];
        // Leaves of one centre differ from it by 8 bits and from each other by 16: well inside it.
        for (int bit = 0; bit < 8; ++bit) {
          const int at = (l * 8 + bit) % 256;
          leaf[static_cast<std::size_t>(at / 8)] ^= static_cast<std::uint8_t>(1u << (at % 8));
        }
        nodes.push_back({static_cast<NodeId>(c + 1), true, leaf, 1.f});
        leaves_.push_back(leaf);
      }
    }
    vocabulary_ = Vocabulary(branching, 2, BowScoring::kL1, BowWeighting::kTfIdf, nodes);
  }

  const Vocabulary& vocabulary() const { return vocabulary_; }
  // Word ids follow node-id order: leaves of centre c are words c*k .. c*k+k-1.
  const Descriptor& word_descriptor(WordId word) const { return leaves_[word]; }

  // The descriptors of an image holding these words (a word listed twice appears twice).
  std::vector<Descriptor> image(const std::vector<WordId>& words) const {
    std::vector<Descriptor> out;
    for (const WordId w : words) out.push_back(leaves_[w]);
    return out;
  }

  static Descriptor random_descriptor(std::mt19937_64& rng) { return test::random_descriptor(rng); }

 private:
  Vocabulary vocabulary_;
  std::vector<Descriptor> leaves_;
};

}  // namespace heslam::test
