#include "nn/serialization.hpp"

#include "core/error.hpp"
#include "nn/architecture.hpp"

namespace lb::nn {

namespace {

std::string describe_shape(const std::vector<hsize_t>& dims)
{
    std::string s = "(";
    for (std::size_t i = 0; i < dims.size(); ++i) s += (i ? ", " : "") + std::to_string(dims[i]);
    return s + (dims.size() == 1 ? ",)" : ")");
}

void check_shape(const h5::File& file, const std::string& name, const std::vector<hsize_t>& expected)
{
    const auto dims = file.shape(name);
    if (dims != expected)
        throw IoError("HDF5 file '" + file.path() + "', '" + name + "': shape " + describe_shape(dims) +
                      " does not match the architecture's " + describe_shape(expected));
}

/// IoError naming the file and dataset if `value` holds a NaN or an infinity (or, with
/// `non_negative`, a negative entry): a network loaded from it would compute NaN silently.
template <typename Derived>
void require_finite(const h5::File& file, const std::string& name, const Eigen::DenseBase<Derived>& value,
                    bool non_negative = false)
{
    if (!value.allFinite())
        throw IoError("HDF5 file '" + file.path() + "', '" + name + "': non-finite value (NaN or inf)");
    if (non_negative && value.size() > 0 && value.minCoeff() < 0)
        throw IoError("HDF5 file '" + file.path() + "', '" + name + "': negative value");
}

bool ends_with(const std::string& s, const std::string& suffix)
{
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

} // namespace

void save_network(h5::File& file, const std::string& prefix, Sequential& net, const Standardizer* standardizer)
{
    const bool with_standardizer = standardizer != nullptr && !standardizer->empty();
    if (with_standardizer && standardizer->features() != net.in_features())
        throw std::invalid_argument("save_network: standardizer width " + std::to_string(standardizer->features()) +
                                    " does not match the network input " + std::to_string(net.in_features()));
    for (const auto& p : net.parameters(prefix)) {
        if (p.vector)
            file.write(p.name, VectorXd(p.value.col(0)));
        else
            file.write(p.name, MatrixXd(p.value));
    }
    for (const auto& b : net.buffers(prefix)) {
        if (b.integer) {
            const double count = b.value(0, 0);
            file.write_array(b.name, {}, &count);  // a scalar, like torch's num_batches_tracked
        } else {
            file.write(b.name, VectorXd(b.value.col(0)));
        }
    }
    if (with_standardizer) {
        file.write(prefix + "standardizer.mean", standardizer->mean());
        file.write(prefix + "standardizer.std", standardizer->stddev());
    }
    file.set_attribute("/", prefix + "architecture", describe_architecture(net, with_standardizer));
}

LoadedNetwork load_network(const h5::File& file, const std::string& prefix)
{
    const std::string key = prefix + "architecture";
    if (!file.has_attribute("/", key))
        throw IoError("HDF5 file '" + file.path() + "': no attribute '" + key + "' (no network saved under prefix '" +
                      prefix + "')");
    const std::string description = file.attribute_string("/", key);
    Architecture arch;
    try {
        arch = parse_architecture(description);
    } catch (const IoError& e) {
        throw IoError("HDF5 file '" + file.path() + "', attribute '" + key + "': " + e.what());
    }
    LoadedNetwork out;
    out.network = std::move(arch.network);
    for (auto& p : out.network.parameters(prefix)) {
        if (p.vector) {
            check_shape(file, p.name, {hsize_t(p.value.rows())});
            p.value.col(0) = file.read_vector(p.name);
        } else {
            check_shape(file, p.name, {hsize_t(p.value.rows()), hsize_t(p.value.cols())});
            p.value = file.read_matrix(p.name);
        }
        require_finite(file, p.name, p.value);
    }
    for (auto& b : out.network.buffers(prefix)) {
        if (b.integer) {
            std::vector<hsize_t> dims;
            const std::vector<double> v = file.read_array(b.name, dims);
            if (v.size() != 1) throw IoError("HDF5 file '" + file.path() + "', '" + b.name + "': expected a scalar");
            b.value(0, 0) = v[0];
            require_finite(file, b.name, b.value, /*non_negative=*/true);
        } else {
            check_shape(file, b.name, {hsize_t(b.value.rows())});
            b.value.col(0) = file.read_vector(b.name);
            // A negative running variance makes sqrt(var + eps) NaN at inference.
            require_finite(file, b.name, b.value, /*non_negative=*/ends_with(b.name, "running_var"));
        }
    }
    if (arch.has_standardizer) {
        const std::string m = prefix + "standardizer.mean", s = prefix + "standardizer.std";
        const Index n = out.network.in_features();
        check_shape(file, m, {hsize_t(n)});
        check_shape(file, s, {hsize_t(n)});
        const VectorXd mean = file.read_vector(m), stddev = file.read_vector(s);
        require_finite(file, m, mean);
        require_finite(file, s, stddev);
        try {
            out.standardizer.emplace(mean, stddev);
        } catch (const std::invalid_argument& e) {
            throw IoError("HDF5 file '" + file.path() + "', '" + s + "': " + e.what());
        }
    }
    return out;
}

void save_network(const std::string& path, const std::string& prefix, Sequential& net, const Standardizer* standardizer)
{
    h5::write_file_atomically(path, [&](h5::File& file) {
        save_network(file, prefix, net, standardizer);
    });
}

LoadedNetwork load_network(const std::string& path, const std::string& prefix)
{
    const h5::File file = h5::File::open(path);
    return load_network(file, prefix);
}

void save_adam_state(h5::File& file, const std::string& prefix, const Adam& adam,
                     const std::vector<ParameterRef>& params)
{
    const AdamState& s = adam.state();
    for (size_t i = 0; i < params.size() && i < s.m.size(); ++i) {
        file.write(prefix + "adam/m/" + params[i].name, s.m[i]);
        file.write(prefix + "adam/v/" + params[i].name, s.v[i]);
    }
    file.set_attribute("/", prefix + "adam_step", (long long)s.step);
}

void load_adam_state(const h5::File& file, const std::string& prefix, Adam& adam,
                     const std::vector<ParameterRef>& params)
{
    AdamState s;
    s.step = file.attribute_int("/", prefix + "adam_step");
    if (s.step > 0) {
        for (const ParameterRef& p : params) {
            s.m.push_back(file.read_matrix(prefix + "adam/m/" + p.name));
            s.v.push_back(file.read_matrix(prefix + "adam/v/" + p.name));
            require_finite(file, prefix + "adam/m/" + p.name, s.m.back());
            // v is a running mean of squared gradients: sqrt(v) needs v ≥ 0.
            require_finite(file, prefix + "adam/v/" + p.name, s.v.back(), /*non_negative=*/true);
            if (s.m.back().rows() != p.value.rows() || s.m.back().cols() != p.value.cols()) {
                throw IoError("'" + file.path() + "': optimiser state for '" + p.name + "' has the wrong shape");
            }
        }
    }
    try {
        adam.set_state(std::move(s));
    } catch (const std::invalid_argument& e) {
        throw IoError("'" + file.path() + "': " + e.what());
    }
}

} // namespace lb::nn
