#pragma once
/// JSON documents that keep their keys in file order (nlohmann::ordered_json), parsed in time
/// linear in their size.
///
/// nlohmann's own parser inserts each key into an ordered_json object by a linear search for
/// a key already there, so an object of n keys takes time n^2 (seconds on a file of many
/// material names; figures: docs/notes/2026-11-29-figures-from-code-comments.md).
/// parse_ordered_json builds the same document through nlohmann's SAX interface with a hash
/// index per open object: the same keys in the same order, a repeated key keeping its first
/// place and its last value, as nlohmann's parser gives.

#include <nlohmann/json.hpp>
#include <string_view>

namespace rp {

/// The document `text` holds: strict JSON (one value, nothing after it but blanks), comments
/// refused. Throws what nlohmann::ordered_json::parse would (parse_error with the byte
/// offset, out_of_range for a number beyond a double).
nlohmann::ordered_json parse_ordered_json(std::string_view text);

}  // namespace rp
