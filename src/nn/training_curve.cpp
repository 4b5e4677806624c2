#include "nn/training_curve.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "core/error.hpp"
#include "io/hdf5.hpp"

namespace lb::nn {

namespace {

constexpr const char* kStagesKey = "training_curve.stages";
constexpr const char* kGroup = "training_curve/";

VectorXd as_vector(const std::vector<double>& v)
{
    return Eigen::Map<const VectorXd>(v.data(), Index(v.size()));
}

std::vector<double> as_std(const VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }

bool valid_stage_name(const std::string& name)
{
    if (name.empty()) return false;
    for (char ch : name) {
        const bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '_';
        if (!ok) return false;
    }
    return true;
}

} // namespace

void save_curve_data(h5::File& file, const std::string& group, const TrainingCurve& curve)
{
    if (curve.train_loss.empty()) return;
    if (curve.has_validation() && curve.validation_loss.size() != curve.train_loss.size())
        throw std::invalid_argument("save_curve_data: " + std::to_string(curve.validation_loss.size()) +
                                    " validation losses for " + std::to_string(curve.train_loss.size()) + " epochs");
    file.write(group + "/train_loss", as_vector(curve.train_loss));
    if (curve.has_validation()) file.write(group + "/validation_loss", as_vector(curve.validation_loss));
}

TrainingCurve load_curve_data(const h5::File& file, const std::string& group)
{
    TrainingCurve curve;
    if (!file.exists(group + "/train_loss")) return curve;
    curve.train_loss = as_std(file.read_vector(group + "/train_loss"));
    if (file.exists(group + "/validation_loss")) {
        curve.validation_loss = as_std(file.read_vector(group + "/validation_loss"));
        if (curve.validation_loss.size() != curve.train_loss.size())
            throw IoError("'" + file.path() + "': " + group + "/validation_loss has " +
                          std::to_string(curve.validation_loss.size()) + " entries but " + group + "/train_loss has " +
                          std::to_string(curve.train_loss.size()) + " (one per epoch each)");
    }
    return curve;
}

void save_training_curves(h5::File& file, const std::string& prefix, const TrainingCurves& curves)
{
    std::string stages;
    for (const TrainingCurve& c : curves) {
        if (!valid_stage_name(c.stage))
            throw std::invalid_argument("save_training_curves: invalid stage name '" + c.stage + "'");
        if (c.train_loss.empty()) continue;
        save_curve_data(file, prefix + kGroup + c.stage, c);
        stages += (stages.empty() ? "" : ",") + c.stage;
    }
    if (!stages.empty()) file.set_attribute("/", prefix + kStagesKey, stages);
}

TrainingCurves load_training_curves(const h5::File& file, const std::string& prefix)
{
    TrainingCurves curves;
    if (!file.has_attribute("/", prefix + kStagesKey)) return curves;
    const std::string stages = file.attribute_string("/", prefix + kStagesKey);
    std::size_t begin = 0;
    while (begin <= stages.size()) {
        std::size_t end = stages.find(',', begin);
        if (end == std::string::npos) end = stages.size();
        const std::string stage = stages.substr(begin, end - begin);
        begin = end + 1;
        if (!valid_stage_name(stage))
            throw IoError("'" + file.path() + "': attribute '" + prefix + kStagesKey + "' lists an invalid stage '" +
                          stage + "' (\"" + stages + "\")");
        const std::string group = prefix + kGroup + stage;
        if (!file.exists(group + "/train_loss"))
            throw IoError("'" + file.path() + "': the training curve of stage '" + stage + "' is listed in '" + prefix +
                          kStagesKey + "' but " + group + "/train_loss is missing");
        TrainingCurve c = load_curve_data(file, group);
        c.stage = stage;
        curves.push_back(std::move(c));
    }
    return curves;
}

double last_train_loss(const TrainingCurves& curves)
{
    for (auto it = curves.rbegin(); it != curves.rend(); ++it) {
        if (!it->train_loss.empty()) return it->train_loss.back();
    }
    return std::numeric_limits<double>::quiet_NaN();
}

namespace {

/// Index of the smallest finite entry (-1 if none).
long argmin_finite(const std::vector<double>& v)
{
    long best = -1;
    for (std::size_t i = 0; i < v.size(); ++i) {
        if (std::isfinite(v[i]) && (best < 0 || v[i] < v[std::size_t(best)])) best = long(i);
    }
    return best;
}

/// The first finite entry (-1 if none).
long first_finite(const std::vector<double>& v)
{
    for (std::size_t i = 0; i < v.size(); ++i) {
        if (std::isfinite(v[i])) return long(i);
    }
    return -1;
}

std::string loss_text(double v)
{
    char text[32];
    std::snprintf(text, sizeof text, "%.4g", v);
    return text;
}

} // namespace

std::string describe_curve(const TrainingCurve& c)
{
    if (c.train_loss.empty()) return "0 epochs";
    std::string out = std::to_string(c.epochs()) + (c.epochs() == 1 ? " epoch" : " epochs") + "; loss ";
    const long first = first_finite(c.train_loss);
    const long lowest = argmin_finite(c.train_loss);
    if (first < 0) {
        out += "not recorded";
    } else {
        out += loss_text(c.train_loss[std::size_t(first)]) + " first";
        if (first > 0) out += " (epoch " + std::to_string(first + 1) + ")";
        out += ", " + loss_text(c.train_loss[std::size_t(lowest)]) + " min (epoch " + std::to_string(lowest + 1) +
               "), " + loss_text(c.train_loss.back()) + " last";
    }
    long unknown = 0;
    for (double v : c.train_loss) unknown += std::isnan(v) ? 1 : 0;
    if (unknown > 0) out += " (" + std::to_string(unknown) + " epochs not recorded)";
    if (c.has_validation()) {
        const long best = argmin_finite(c.validation_loss);
        if (best < 0)
            out += "; validation not recorded";
        else
            out += "; validation " + loss_text(c.validation_loss[std::size_t(best)]) + " min (epoch " +
                   std::to_string(best + 1) + "), " + loss_text(c.validation_loss.back()) + " last";
    }
    return out;
}

} // namespace lb::nn
