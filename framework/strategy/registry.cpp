#include "framework/strategy/registry.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace ndc {
namespace {

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

/// A value as a spec and summary.json spell it.
std::string formatValue(const ParameterSpec& spec, double value) {
  if (spec.type == ParameterType::kBoolean) return value != 0 ? "true" : "false";
  if (spec.type == ParameterType::kInteger) return std::to_string(static_cast<long long>(value));
  // The shortest text that reads back as the same double (0.45, not 0.45000000000000001).
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string rangeText(const ParameterSpec& spec) {
  if (spec.type == ParameterType::kBoolean) return "true or false";
  const char* what = spec.type == ParameterType::kInteger ? "an integer" : "a number";
  return std::string(what) + " in " + formatValue(spec, spec.min) + ".." +
         formatValue(spec, spec.max);
}

/// The value of `text` for `spec`, or false when it is none.
bool parseValue(const ParameterSpec& spec, std::string_view text, double& value) {
  if (spec.type == ParameterType::kBoolean) {
    if (text == "true" || text == "1") return value = 1, true;
    if (text == "false" || text == "0") return value = 0, true;
    return false;
  }
  if (spec.type == ParameterType::kInteger) {
    long long v = 0;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (error != std::errc() || end != text.data() + text.size()) return false;
    value = static_cast<double>(v);
  } else {
    const std::string s(text);
    char* end = nullptr;
    value = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(value)) return false;
  }
  return spec.min <= value && value <= spec.max;
}

}  // namespace

Parameters::Parameters(const std::vector<ParameterSpec>& specs) {
  for (const ParameterSpec& spec : specs) values_.emplace_back(spec, spec.defaultValue);
}

double Parameters::real(std::string_view name) const {
  for (const auto& [spec, value] : values_)
    if (spec.name == name) return value;
  throw std::logic_error("strategy parameter '" + std::string(name) + "' is not declared");
}

void Parameters::set(std::string_view name, std::string_view text, const std::string& where) {
  for (auto& [spec, value] : values_) {
    if (spec.name != name) continue;
    if (!parseValue(spec, text, value))
      throw UsageError(where + ": '" + std::string(text) + "' is not " + rangeText(spec));
    return;
  }
  throw std::logic_error("strategy parameter '" + std::string(name) + "' is not declared");
}

std::string Parameters::json() const {
  std::string out = "{";
  for (const auto& [spec, value] : values_)
    out += (out.size() > 1 ? ", \"" : "\"") + spec.name + "\": " + formatValue(spec, value);
  return out + "}";
}

std::string Parameters::text() const {
  std::string out;
  for (const auto& [spec, value] : values_)
    out += (out.empty() ? "" : ",") + spec.name + "=" + formatValue(spec, value);
  return out;
}

std::string unknownModelMessage(const std::string& family, std::string_view name,
                                const std::vector<std::string>& known) {
  return "unknown " + family + " strategy '" + std::string(name) + "' (known: " + joined(known) +
         ")";
}

void checkModelName(const std::string& family, const std::string& name,
                    const std::vector<std::string>& taken) {
  bool valid = !name.empty() && name[0] >= 'a' && name[0] <= 'z';
  for (char c : name)
    valid = valid && ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-');
  if (!valid)
    throw std::logic_error(family + " strategy name '" + name + "' is not [a-z][a-z0-9-]*");
  for (const std::string& t : taken)
    if (t == name) throw std::logic_error(family + " strategy '" + name + "' is registered twice");
}

StrategyChoice parseStrategySpec(std::string_view spec, const std::string& family,
                                 const std::vector<ModelSpec>& models) {
  const std::size_t colon = spec.find(':');
  StrategyChoice choice;
  choice.name = std::string(spec.substr(0, colon));
  const ModelSpec* model = nullptr;
  for (const ModelSpec& m : models)
    if (m.name == choice.name) model = &m;
  if (!model) {
    std::vector<std::string> known;
    for (const ModelSpec& m : models) known.push_back(m.name);
    throw UsageError(unknownModelMessage(family, choice.name, known));
  }
  choice.parameters = Parameters(model->parameters);
  if (colon == std::string_view::npos) return choice;

  // The parameters: key=value, separated by commas, each key at most once.
  std::vector<std::string> keys, seen;
  for (const ParameterSpec& p : model->parameters) keys.push_back(p.name);
  const std::string prefix = family + " strategy '" + std::string(spec) + "'";
  std::string_view rest = spec.substr(colon + 1);
  if (rest.empty()) throw UsageError(prefix + ": no parameter after ':'");
  while (true) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    const std::size_t equals = item.find('=');
    const std::string key(item.substr(0, equals));
    if (equals == std::string_view::npos || key.empty())
      throw UsageError(prefix + ": '" + std::string(item) + "' is not KEY=VALUE");
    bool known = false;
    for (const std::string& k : keys) known = known || k == key;
    if (!known)
      throw UsageError(prefix + ": unknown parameter '" + key + "' (" +
                       (keys.empty() ? std::string("it has none") : "known: " + joined(keys)) +
                       ")");
    for (const std::string& s : seen)
      if (s == key) throw UsageError(prefix + ": parameter '" + key + "' is given twice");
    seen.push_back(key);
    choice.parameters.set(key, item.substr(equals + 1), prefix + ", " + key);
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  return choice;
}

std::string registryHelp(const std::vector<ModelSpec>& models, std::string_view defaultName) {
  std::string out;
  for (const ModelSpec& m : models)
    out += (out.empty() ? "" : ", ") + m.name + (m.name == defaultName ? " (default)" : "");
  for (const ModelSpec& m : models)
    for (const ParameterSpec& p : m.parameters)
      out += "; " + m.name + ":" + p.name + "=VALUE " + p.doc + " (" + rangeText(p) + ", default " +
             formatValue(p, p.defaultValue) + ")";
  return out;
}

std::string registryMarkdown(const std::string& family, const std::vector<ModelSpec>& models) {
  std::ostringstream out;
  out << "| " << family << " | parameters (default) | what it does |\n|---|---|---|\n";
  for (const ModelSpec& m : models) {
    std::string parameters;
    for (const ParameterSpec& p : m.parameters)
      parameters += (parameters.empty() ? "" : ", ") + std::string("`") + p.name + "` (" +
                    formatValue(p, p.defaultValue) + ")";
    out << "| `" << m.name << "` | " << (parameters.empty() ? "none" : parameters) << " | " << m.doc
        << " |\n";
  }
  return out.str();
}

}  // namespace ndc
