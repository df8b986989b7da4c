// BlockSparseCholesky against Eigen's dense LL^T on block-sparse SPD matrices shaped like a pose
// graph's normal equations: a chain of blocks with a band of neighbours, and a loop closing it.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/SparseCore>

#include "components/core/solve/block_sparse_cholesky.hpp"

namespace heslam {
namespace {

// Sum of J^T J over random "edges" between blocks (each a random D x D Jacobian pair), plus a small
// multiple of the identity so the matrix is positive definite; returned dense.
Eigen::MatrixXd block_matrix(int blocks, int D, const std::vector<std::pair<int, int>>& links, std::mt19937& random) {
  std::normal_distribution<double> normal;
  const int n = blocks * D;
  Eigen::MatrixXd H = 1e-3 * Eigen::MatrixXd::Identity(n, n);
  for (const auto& [a, b] : links) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(D, n);
    for (int r = 0; r < D; ++r) {
      for (int c = 0; c < D; ++c) {
        J(r, D * a + c) = normal(random);
        J(r, D * b + c) = normal(random);
      }
    }
    H += J.transpose() * J;
  }
  return H;
}

// The lower triangle of H's blocks that links (and the diagonal) make present, all entries of each.
Eigen::SparseMatrix<double> lower_blocks(const Eigen::MatrixXd& H, int D,
                                         const std::vector<std::pair<int, int>>& links) {
  std::vector<Eigen::Triplet<double>> entries;
  const auto add_block = [&](int row, int column) {
    for (int c = 0; c < D; ++c) {
      for (int r = 0; r < D; ++r) {
        if (D * row + r >= D * column + c)
          entries.emplace_back(D * row + r, D * column + c, H(D * row + r, D * column + c));
      }
    }
  };
  const int blocks = static_cast<int>(H.rows()) / D;
  for (int j = 0; j < blocks; ++j) add_block(j, j);
  std::vector<std::pair<int, int>> seen;
  for (const auto& [a, b] : links) {
    const std::pair<int, int> block{std::max(a, b), std::min(a, b)};
    if (block.first == block.second || std::find(seen.begin(), seen.end(), block) != seen.end()) continue;
    seen.push_back(block);
    add_block(block.first, block.second);
  }
  Eigen::SparseMatrix<double> lower(H.rows(), H.cols());
  lower.setFromTriplets(entries.begin(), entries.end());
  return lower;
}

// A chain of `blocks` with links to the next `band` blocks, and optionally a loop: the last `band`
// blocks linked to the first `band`.
std::vector<std::pair<int, int>> chain(int blocks, int band, bool loop) {
  std::vector<std::pair<int, int>> links;
  for (int a = 0; a < blocks; ++a) {
    for (int b = a + 1; b <= a + band && b < blocks; ++b) links.emplace_back(a, b);
  }
  if (loop) {
    for (int a = blocks - band; a < blocks; ++a) {
      for (int b = 0; b < band; ++b) links.emplace_back(a, b);
    }
  }
  return links;
}

void expect_solves_like_dense(int blocks, int D, const std::vector<std::pair<int, int>>& links, unsigned seed) {
  std::mt19937 random(seed);
  const Eigen::MatrixXd H = block_matrix(blocks, D, links, random);
  const Eigen::SparseMatrix<double> lower = lower_blocks(H, D, links);
  BlockSparseCholesky cholesky;
  cholesky.analyze(lower, D);
  ASSERT_TRUE(cholesky.factorize(lower));
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(H.rows(), -1.0, 2.0);
  const Eigen::VectorXd expected = H.llt().solve(b);
  const Eigen::VectorXd x = cholesky.solve(b);
  EXPECT_LT((x - expected).norm(), 1e-9 * expected.norm()) << blocks << " blocks of " << D;
  EXPECT_LT((H * x - b).norm(), 1e-9 * b.norm());
  // A second factorization of other values on the same pattern.
  const Eigen::SparseMatrix<double> doubled = 2.0 * lower;
  ASSERT_TRUE(cholesky.factorize(doubled));
  EXPECT_LT((cholesky.solve(b) - 0.5 * expected).norm(), 1e-9 * expected.norm());
}

TEST(BlockSparseCholesky, SolvesABandedChain) {
  expect_solves_like_dense(60, 6, chain(60, 5, false), 1);
  expect_solves_like_dense(40, 4, chain(40, 3, false), 2);
}

TEST(BlockSparseCholesky, SolvesAChainClosedByALoop) {
  expect_solves_like_dense(80, 6, chain(80, 6, true), 3);
  expect_solves_like_dense(50, 4, chain(50, 2, true), 4);
}

TEST(BlockSparseCholesky, SolvesRandomLinksAndIsolatedBlocks) {
  std::mt19937 random(5);
  std::uniform_int_distribution<int> block(0, 69);
  std::vector<std::pair<int, int>> links;
  for (int k = 0; k < 120; ++k) links.emplace_back(block(random), block(random));
  expect_solves_like_dense(70, 6, links, 6);  // some blocks touch no link: a diagonal block alone
  expect_solves_like_dense(3, 6, {}, 7);
  expect_solves_like_dense(12, 1, chain(12, 11, false), 8);  // scalar and dense
}

TEST(BlockSparseCholesky, ReportsAMatrixThatIsNotPositiveDefinite) {
  std::mt19937 random(9);
  const std::vector<std::pair<int, int>> links = chain(20, 3, true);
  Eigen::MatrixXd H = block_matrix(20, 6, links, random);
  H(60, 60) = -1.0;
  const Eigen::SparseMatrix<double> lower = lower_blocks(H, 6, links);
  BlockSparseCholesky cholesky;
  cholesky.analyze(lower, 6);
  EXPECT_FALSE(cholesky.factorize(lower));
  EXPECT_THROW(cholesky.analyze(lower, 7), std::invalid_argument);
}

}  // namespace
}  // namespace heslam
