#include "io/ordered_json.h"

#include <cstddef>
#include <string>
#include <unordered_map>
#include <vector>

namespace rp {

namespace {

using Json = nlohmann::ordered_json;

/// nlohmann's SAX events into an ordered_json, appending each new key to its object and
/// finding a repeated one through the object's index.
class OrderedBuilder {
 public:
  explicit OrderedBuilder(Json& root) : root_(root) {}

  bool null() { return value(nullptr); }
  bool boolean(bool b) { return value(b); }
  bool number_integer(Json::number_integer_t n) { return value(n); }
  bool number_unsigned(Json::number_unsigned_t n) { return value(n); }
  bool number_float(Json::number_float_t x, const Json::string_t&) { return value(x); }
  bool string(Json::string_t& s) { return value(std::move(s)); }
  bool binary(Json::binary_t& b) { return value(Json::binary(std::move(b))); }

  bool start_object(std::size_t) {
    open_.push_back({value(Json::object_t()), {}});
    return true;
  }
  bool key(Json::string_t& k) {
    Open& o = open_.back();
    Json::object_t& members = *o.value->get_ptr<Json::object_t*>();
    const auto [at, added] = o.index.try_emplace(k, members.size());
    // A repeated key keeps its place; its new value replaces the old one.
    if (added) members.emplace_back(std::move(k), nullptr);
    slot_ = &(members.begin() + std::ptrdiff_t(at->second))->second;
    return true;
  }
  bool end_object() {
    open_.pop_back();
    return true;
  }
  bool start_array(std::size_t) {
    open_.push_back({value(Json::array_t()), {}});
    return true;
  }
  bool end_array() {
    open_.pop_back();
    return true;
  }
  template <typename Exception>
  bool parse_error(std::size_t, const std::string&, const Exception& e) {
    throw e;
  }

 private:
  struct Open {
    Json* value;  ///< an object or array being filled (its parent is complete up to it)
    std::unordered_map<std::string, size_t> index;  ///< an object's keys: their places
  };

  /// Puts `v` where the document is at: the root, the end of the open array, or the slot of
  /// the key just read. Returns where it went.
  template <typename T>
  Json* value(T&& v) {
    if (open_.empty()) {
      root_ = Json(std::forward<T>(v));
      return &root_;
    }
    Json& parent = *open_.back().value;
    if (parent.is_array()) {
      parent.get_ptr<Json::array_t*>()->emplace_back(std::forward<T>(v));
      return &parent.get_ptr<Json::array_t*>()->back();
    }
    *slot_ = Json(std::forward<T>(v));
    return slot_;
  }

  Json& root_;
  std::vector<Open> open_;
  Json* slot_ = nullptr;
};

}  // namespace

nlohmann::ordered_json parse_ordered_json(std::string_view text) {
  Json root;
  OrderedBuilder builder(root);
  Json::sax_parse(text, &builder, nlohmann::detail::input_format_t::json, /*strict=*/true, /*ignore_comments=*/false);
  return root;
}

}  // namespace rp
