// Named parameters settable from the command line (`--set lpv.iterations=16`).
// Each pass declares its parameters with a default, a range and a one-line description;
// `gi render --list-params` prints them. Unknown names and bad values are errors, never ignored.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace gi {

class ParamSet {
public:
  enum class Kind { Int, Float, Bool, Choice };
  struct Param {
    std::string name, description;
    Kind kind = Kind::Float;
    double value = 0, lo = 0, hi = 0;  // Int/Float/Bool value (Bool: 0/1) and allowed range
    std::vector<std::string> choices;  // Choice: allowed words; value = index
  };

  void addInt(const std::string& name, int def, int lo, int hi, const std::string& description);
  void addFloat(const std::string& name, double def, double lo, double hi, const std::string& description);
  void addBool(const std::string& name, bool def, const std::string& description);
  void addChoice(const std::string& name, const std::string& def, std::vector<std::string> choices,
                 const std::string& description);

  // "name=value". Throws gi::Error naming the parameter and what was expected.
  void set(const std::string& assignment);
  void set(const std::string& name, const std::string& value);

  int getInt(const std::string& name) const;
  float getFloat(const std::string& name) const;
  bool getBool(const std::string& name) const;
  std::string getChoice(const std::string& name) const;
  bool has(const std::string& name) const { return params_.count(name) != 0; }

  const std::map<std::string, Param>& all() const { return params_; }
  std::string valueString(const std::string& name) const;
  std::string describe() const;  // one line per parameter: name = value [range]  description

private:
  const Param& find(const std::string& name, Kind kind) const;
  std::map<std::string, Param> params_;
};

}  // namespace gi
