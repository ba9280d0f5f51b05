// The documents as a reader meets them: README.md and docs/ link only to what exists, the CLI
// reference names every flag the commands offer, and the README stays a user's page.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/build_paths.h"
#include "tests/support/shell.h"

namespace {

namespace fs = std::filesystem;

const fs::path kRoot = rp::test::kSourceDir;

std::string text_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// README.md and every .md file under docs/.
std::vector<fs::path> documents() {
  std::vector<fs::path> files{kRoot / "README.md"};
  for (const auto& e : fs::recursive_directory_iterator(kRoot / "docs"))
    if (e.is_regular_file() && e.path().extension() == ".md") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

/// The lines of `text`, those of fenced code blocks and inline code spans blanked (links and
/// headings inside code are not links or headings); element i is line i + 1.
std::vector<std::string> prose_lines(const std::string& text) {
  std::vector<std::string> lines;
  bool fenced = false;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    start = end + 1;
    const size_t lead = line.find_first_not_of(' ');
    if (lead != std::string::npos && line.compare(lead, 3, "```") == 0) {
      fenced = !fenced;
      line.clear();
    }
    if (fenced) line.clear();
    bool code = false;
    for (char& c : line) {
      if (c == '`')
        code = !code;
      else if (code)
        c = ' ';
    }
    lines.push_back(line);
  }
  return lines;
}

/// GitHub's anchor of a heading: lower case, punctuation but '-' and '_' dropped, spaces to
/// '-', backticks dropped; a repeated anchor gets -1, -2, ...
std::set<std::string> anchors_of(const std::string& text) {
  std::set<std::string> anchors;
  std::map<std::string, int> seen;
  bool fenced = false;
  std::istringstream in(text);
  static const std::regex explicit_anchor(R"re(<a (?:id|name)="([^"]+)")re");
  for (std::string line; std::getline(in, line);) {
    const size_t lead = line.find_first_not_of(' ');
    if (lead != std::string::npos && line.compare(lead, 3, "```") == 0) fenced = !fenced;
    if (fenced) continue;
    for (std::sregex_iterator it(line.begin(), line.end(), explicit_anchor), end; it != end; ++it)
      anchors.insert((*it)[1]);
    if (line.empty() || line[0] != '#') continue;
    const size_t hashes = line.find_first_not_of('#');
    if (hashes == std::string::npos || hashes > 6 || line[hashes] != ' ') continue;
    std::string slug;
    for (const char c : line.substr(hashes + 1)) {
      const unsigned char u = static_cast<unsigned char>(c);
      if (u >= 0x80 || std::isalnum(u) || c == '-' || c == '_')
        slug += char(std::tolower(u));
      else if (c == ' ')
        slug += '-';
    }
    const int n = seen[slug]++;
    anchors.insert(n == 0 ? slug : slug + "-" + std::to_string(n));
  }
  return anchors;
}

TEST(Docs, EveryRelativeLinkAndAnchorResolves) {
  std::map<fs::path, std::set<std::string>> anchors;
  for (const fs::path& doc : documents()) anchors[fs::weakly_canonical(doc)] = anchors_of(text_of(doc));
  static const std::regex link(R"re(\]\(([^)\s]+)(?:\s+"[^"]*")?\))re");
  size_t checked = 0;
  for (const fs::path& doc : documents()) {
    int number = 0;
    for (const std::string& line : prose_lines(text_of(doc))) {
      ++number;
      for (std::sregex_iterator it(line.begin(), line.end(), link), end; it != end; ++it) {
        const std::string target = (*it)[1];
        if (target.find("://") != std::string::npos || target.rfind("mailto:", 0) == 0) continue;
        const size_t hash = target.find('#');
        const std::string path = target.substr(0, hash),
                          anchor = hash == std::string::npos ? "" : target.substr(hash + 1);
        const fs::path file = path.empty() ? doc : fs::weakly_canonical(doc.parent_path() / path);
        const std::string where = fs::relative(doc, kRoot).string() + ": " + target;
        ++checked;
        if (!fs::exists(file)) {
          ADD_FAILURE() << where << ": no such file";
          continue;
        }
        if (anchor.empty()) continue;
        const auto a = anchors.find(fs::weakly_canonical(file));
        if (a == anchors.end()) {
          ADD_FAILURE() << where << ": an anchor into a file that is not a document";
          continue;
        }
        EXPECT_TRUE(a->second.count(anchor)) << where << ": no heading has the anchor #" << anchor;
      }
    }
  }
  EXPECT_GT(checked, 20u) << "the documents link to each other";
}

TEST(Docs, TheCliReferenceNamesEveryFlagOfEveryCommand) {
  const std::string reference = text_of(kRoot / "docs" / "cli.md");
  ASSERT_FALSE(reference.empty()) << "docs/cli.md";
  static const std::regex flag(R"re((--[a-z][a-z0-9-]+))re");
  for (const std::string command :
       {"", "render", "info", "backends", "trace", "points", "diff", "bench", "chart", "stability", "domains"}) {
    const rp::test::ShellResult r = rp::test::run_shell(std::string(rp::test::kRaypackExe) + " " + command + " --help");
    ASSERT_EQ(r.status, 0) << command << ": " << r.output;
    std::set<std::string> flags;
    for (std::sregex_iterator it(r.output.begin(), r.output.end(), flag), end; it != end; ++it) flags.insert((*it)[1]);
    EXPECT_FALSE(flags.empty()) << command;
    for (const std::string& f : flags)
      EXPECT_NE(reference.find("`" + f), std::string::npos)
          << "raypack " << command << " " << f << " is not in docs/cli.md";
  }
  // Every format that loads is named where a scene is asked for.
  const rp::test::ShellResult r = rp::test::run_shell(std::string(rp::test::kRaypackExe) + " render --help");
  EXPECT_NE(r.output.find(".gltf"), std::string::npos) << r.output;
}

TEST(Docs, TheReadmeIsAUsersPageAndUserDocumentsCarryNoHistory) {
  const std::string readme = text_of(kRoot / "README.md");
  EXPECT_LE(std::count(readme.begin(), readme.end(), '\n'), 350) << "README.md: at most 350 lines; the rest in docs/";
  // Commit hashes and tracker numbers belong to docs/notes/ (docs/notes/README.md says why).
  static const std::regex hash(R"re((^|[^0-9A-Za-z_x])([0-9a-f]{7,40})([^0-9A-Za-z_]|$))re");
  static const std::regex tracker(R"re(\b[Ii]ssues? #?[0-9]+\b)re");
  for (const fs::path& doc : documents()) {
    const std::string rel = fs::relative(doc, kRoot).string();
    if (rel.rfind("docs/notes/", 0) == 0) continue;
    int number = 0;
    for (const std::string& line : prose_lines(text_of(doc))) {
      ++number;
      std::smatch m;
      if (std::regex_search(line, m, hash)) {
        const std::string h = m[2];
        const bool letters = h.find_first_of("abcdef") != std::string::npos,
                   digits = h.find_first_of("0123456789") != std::string::npos;
        EXPECT_FALSE(letters && digits) << rel << ":" << number << ": a commit hash? " << h;
      }
      EXPECT_FALSE(std::regex_search(line, tracker)) << rel << ":" << number << ": a tracker number: " << line;
    }
  }
}

}  // namespace
