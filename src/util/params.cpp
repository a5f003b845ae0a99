#include "util/params.h"

#include <cmath>
#include <sstream>

#include "util/error.h"

namespace gi {

void ParamSet::addInt(const std::string& n, int def, int lo, int hi, const std::string& d) {
  params_[n] = Param{n, d, Kind::Int, double(def), double(lo), double(hi), {}};
}
void ParamSet::addFloat(const std::string& n, double def, double lo, double hi, const std::string& d) {
  params_[n] = Param{n, d, Kind::Float, def, lo, hi, {}};
}
void ParamSet::addBool(const std::string& n, bool def, const std::string& d) {
  params_[n] = Param{n, d, Kind::Bool, def ? 1.0 : 0.0, 0, 1, {}};
}
void ParamSet::addChoice(const std::string& n, const std::string& def, std::vector<std::string> choices,
                         const std::string& d) {
  Param p{n, d, Kind::Choice, 0, 0, 0, std::move(choices)};
  for (size_t i = 0; i < p.choices.size(); ++i)
    if (p.choices[i] == def) p.value = double(i);
  params_[n] = p;
}

void ParamSet::set(const std::string& assignment) {
  size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw Error("--set '" + assignment + "': expected name=value");
  set(assignment.substr(0, eq), assignment.substr(eq + 1));
}

void ParamSet::set(const std::string& name, const std::string& value) {
  auto it = params_.find(name);
  if (it == params_.end()) {
    std::string known;
    for (auto& [k, p] : params_) known += (known.empty() ? "" : ", ") + k;
    throw Error("unknown parameter '" + name + "' (known: " + (known.empty() ? "none" : known) + ")");
  }
  Param& p = it->second;
  auto bad = [&](const std::string& expected) {
    return Error("parameter " + name + "=" + value + ": expected " + expected);
  };
  switch (p.kind) {
    case Kind::Bool:
      if (value == "1" || value == "true" || value == "on") p.value = 1;
      else if (value == "0" || value == "false" || value == "off") p.value = 0;
      else throw bad("true or false");
      return;
    case Kind::Choice:
      for (size_t i = 0; i < p.choices.size(); ++i)
        if (p.choices[i] == value) { p.value = double(i); return; }
      {
        std::string c;
        for (auto& s : p.choices) c += (c.empty() ? "" : "|") + s;
        throw bad("one of " + c);
      }
    case Kind::Int:
    case Kind::Float: {
      std::istringstream in(value);
      double v;
      in >> v;
      if (!in || !in.eof() || !std::isfinite(v)) throw bad(p.kind == Kind::Int ? "an integer" : "a number");
      if (p.kind == Kind::Int && v != std::floor(v)) throw bad("an integer");
      if (v < p.lo || v > p.hi) {
        std::ostringstream r;
        r << "a value in [" << p.lo << ", " << p.hi << "]";
        throw bad(r.str());
      }
      p.value = v;
      return;
    }
  }
}

const ParamSet::Param& ParamSet::find(const std::string& name, Kind kind) const {
  auto it = params_.find(name);
  if (it == params_.end() || it->second.kind != kind) throw Error("internal: parameter '" + name + "' not declared with this type");
  return it->second;
}
int ParamSet::getInt(const std::string& n) const { return int(find(n, Kind::Int).value); }
float ParamSet::getFloat(const std::string& n) const { return float(find(n, Kind::Float).value); }
bool ParamSet::getBool(const std::string& n) const { return find(n, Kind::Bool).value != 0; }
std::string ParamSet::getChoice(const std::string& n) const {
  const Param& p = find(n, Kind::Choice);
  return p.choices[size_t(p.value)];
}

std::string ParamSet::valueString(const std::string& name) const {
  const Param& p = params_.at(name);
  std::ostringstream s;
  switch (p.kind) {
    case Kind::Bool: s << (p.value != 0 ? "true" : "false"); break;
    case Kind::Choice: s << p.choices[size_t(p.value)]; break;
    default: s << p.value;
  }
  return s.str();
}

std::string ParamSet::describe() const {
  std::ostringstream s;
  for (auto& [name, p] : params_) {
    s << "  " << name << " = " << valueString(name);
    if (p.kind == Kind::Int || p.kind == Kind::Float) s << "  [" << p.lo << ", " << p.hi << "]";
    if (p.kind == Kind::Choice) {
      s << "  {";
      for (size_t i = 0; i < p.choices.size(); ++i) s << (i ? "|" : "") << p.choices[i];
      s << "}";
    }
    s << "  " << p.description << "\n";
  }
  return s.str();
}

}  // namespace gi
