// A small JSON writer (objects, numbers, strings) and the result documents.
#include "tools/eval/json_output.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace heslam::eval {

namespace {

// Writes `"key": value` members with commas and indentation handled in one place.
class JsonObject {
 public:
  explicit JsonObject(int indent = 0) : indent_(indent) { out_ << "{"; }

  JsonObject& number(const std::string& key, double value) {
    char buffer[40];
    if (std::isfinite(value)) {
      std::snprintf(buffer, sizeof buffer, "%.17g", value);
    } else {
      std::snprintf(buffer, sizeof buffer, "null");
    }
    return raw(key, buffer);
  }
  JsonObject& integer(const std::string& key, long long value) { return raw(key, std::to_string(value)); }
  JsonObject& boolean(const std::string& key, bool value) { return raw(key, value ? "true" : "false"); }
  JsonObject& string(const std::string& key, const std::string& value) { return raw(key, quote(value)); }
  JsonObject& raw(const std::string& key, const std::string& json) {
    out_ << (first_ ? "\n" : ",\n") << std::string(static_cast<std::size_t>(indent_ + 2), ' ') << quote(key) << ": "
         << json;
    first_ = false;
    return *this;
  }
  std::string str() const { return out_.str() + "\n" + std::string(static_cast<std::size_t>(indent_), ' ') + "}"; }

 private:
  static std::string quote(const std::string& text) {
    std::string out = "\"";
    for (const char c : text) {
      if (c == '"' || c == '\\') {
        out += '\\';
        out += c;
      } else if (static_cast<unsigned char>(c) < 0x20) {
        char buffer[8];
        std::snprintf(buffer, sizeof buffer, "\\u%04x", static_cast<unsigned>(c));
        out += buffer;
      } else {
        out += c;
      }
    }
    return out + "\"";
  }

  std::ostringstream out_;
  int indent_;
  bool first_ = true;
};

std::string stats_json(const ErrorStats& s, int indent) {
  return JsonObject(indent)
      .number("rmse", s.rmse)
      .number("mean", s.mean)
      .number("median", s.median)
      .number("std", s.std)
      .number("min", s.min)
      .number("max", s.max)
      .number("sse", s.sse)
      .integer("count", static_cast<long long>(s.count))
      .str();
}

std::string sim3_json(const Sim3& S, int indent) {
  std::ostringstream rotation;
  rotation << "[";
  char buffer[40];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      std::snprintf(buffer, sizeof buffer, "%.17g", S.R(r, c));
      rotation << (r + c == 0 ? "" : ", ") << buffer;
    }
  }
  rotation << "]";
  std::ostringstream translation;
  translation << "[";
  for (int k = 0; k < 3; ++k) {
    std::snprintf(buffer, sizeof buffer, "%.17g", S.t[k]);
    translation << (k == 0 ? "" : ", ") << buffer;
  }
  translation << "]";
  return JsonObject(indent)
      .raw("rotation_row_major", rotation.str())
      .raw("translation", translation.str())
      .number("scale", S.scale)
      .str();
}

JsonObject header(const std::string& metric, const JsonContext& context) {
  JsonObject object;
  object.string("metric", metric)
      .string("gt", context.gt_path)
      .string("est", context.est_path)
      .integer("gt_poses", static_cast<long long>(context.gt_poses))
      .integer("est_poses", static_cast<long long>(context.est_poses))
      .string("association", context.associated_by_time ? "time" : "frame_index");
  if (context.associated_by_time) object.number("max_dt_s", context.max_dt_s);
  return object;
}

}  // namespace

std::string to_json(const ApeResult& ape, const JsonContext& context) {
  return header("ape", context)
             .string("align", align_mode_name(ape.align))
             .raw("alignment", sim3_json(ape.alignment, 2))
             .integer("pairs", static_cast<long long>(ape.translation_m.count))
             .raw("translation_m", stats_json(ape.translation_m, 2))
             .raw("rotation_deg", stats_json(ape.rotation_deg, 2))
             .str() +
         "\n";
}

std::string to_json(const RpeResult& rpe, const JsonContext& context) {
  return header("rpe", context)
             .number("delta", rpe.options.delta)
             .string("delta_unit", delta_unit_name(rpe.options.unit))
             .boolean("all_pairs", rpe.options.all_pairs)
             .string("align", align_mode_name(rpe.options.align))
             .integer("pairs", static_cast<long long>(rpe.pairs.size()))
             .raw("translation_m", stats_json(rpe.translation_m, 2))
             .raw("rotation_deg", stats_json(rpe.rotation_deg, 2))
             .str() +
         "\n";
}

std::string to_json(const KittiResult& kitti, const JsonContext& context) {
  std::ostringstream lengths;
  lengths << "[";
  for (std::size_t i = 0; i < kitti.per_length.size(); ++i) {
    const KittiLengthError& l = kitti.per_length[i];
    lengths << (i == 0 ? "\n    " : ",\n    ")
            << JsonObject(4)
                   .number("length_m", l.length_m)
                   .integer("segments", static_cast<long long>(l.segments))
                   .number("translation_error_percent", l.translation_error_percent)
                   .number("rotation_error_deg_per_100m", l.rotation_error_deg_per_100m)
                   .str();
  }
  lengths << "\n  ]";
  return header("kitti", context)
             .string("align", align_mode_name(kitti.align))
             .raw("alignment", sim3_json(kitti.alignment, 2))
             .integer("pairs", static_cast<long long>(kitti.pairs))
             .integer("segments", static_cast<long long>(kitti.segments.size()))
             .number("translation_error_percent", kitti.translation_error_percent)
             .number("rotation_error_deg_per_100m", kitti.rotation_error_deg_per_100m)
             .number("ate_m", kitti.ate_m)
             .number("rpe_m", kitti.rpe_m)
             .number("rpe_deg", kitti.rpe_deg)
             .raw("per_length", lengths.str())
             .str() +
         "\n";
}

void write_text_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace heslam::eval
