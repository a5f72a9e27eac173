// A test-only surrogate: the verdict of the nearest executed scenario.
#include "nearest_neighbour_surrogate.hpp"

#include <limits>

namespace vsd::test {

namespace {

class NearestNeighbour final : public search::Surrogate {
 public:
  bool guidesSelection() const override { return true; }
  void fit(const search::TrainingSet& data) override { data_ = data; }
  std::vector<double> probability(const search::CandidateSet& candidates,
                                  const search::Criterion& criterion) const override {
    std::vector<double> result;
    for (Eigen::Index c = 0; c < candidates.x.rows(); ++c) {
      Eigen::Index nearest = 0;
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index e = 0; e < data_.x.rows(); ++e) {
        const double distance = (data_.x.row(e) - candidates.x.row(c)).squaredNorm();
        if (distance < best) {
          best = distance;
          nearest = e;
        }
      }
      const Eigen::VectorXd metrics = data_.y.row(nearest).transpose();
      const std::vector<double> values(metrics.data(), metrics.data() + metrics.size());
      result.push_back(criterion.meetsUsed(values) ? 0.9 : 0.1);
    }
    return result;
  }

 private:
  search::TrainingSet data_;
};

}  // namespace

search::SurrogateEntry nearestNeighbourSurrogate() {
  search::SurrogateEntry entry;
  entry.name = "nearest-neighbour";
  entry.description = "the verdict of the nearest executed scenario (test-only)";
  entry.make = [](const search::SurrogateOptions&) -> std::unique_ptr<search::Surrogate> {
    return std::make_unique<NearestNeighbour>();
  };
  return entry;
}

}  // namespace vsd::test
