// SPDX-License-Identifier: MIT
// The code stays in small files with one job and functions of a screen or so: no file in src/
// over 600 lines and no function over 120, except those docs/architecture.md lists with the
// reason (parsers and tables, whose checks read in the order of their format). A file or
// function that grows past the limit fails here until it is split or listed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace strike {
namespace {

namespace fs = std::filesystem;

constexpr size_t kMaxFileLines = 600;
constexpr size_t kMaxFunctionLines = 120;

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<fs::path> sourceFiles() {
  std::vector<fs::path> files;
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(fs::path(STRIKE_SOURCE_DIR) / "src")) {
    const std::string ext = e.path().extension().string();
    if (e.is_regular_file() && (ext == ".cpp" || ext == ".hpp" || ext == ".h" || ext == ".c"))
      files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

/// The path relative to the repository, as the docs write it ("src/audio/analyze.cpp").
std::string repoPath(const fs::path& file) { return fs::relative(file, fs::path(STRIKE_SOURCE_DIR)).generic_string(); }

/// The first cells of the table rows in docs/architecture.md's section whose heading starts
/// with `heading` (up to the next "## ").
std::vector<std::string> listedIn(const std::string& heading) {
  std::istringstream doc(slurp(fs::path(STRIKE_SOURCE_DIR) / "docs" / "architecture.md"));
  std::vector<std::string> cells;
  bool inside = false;
  for (std::string line; std::getline(doc, line);) {
    if (line.rfind("## ", 0) == 0) inside = line.rfind(heading, 0) == 0;
    if (!inside || line.rfind("| ", 0) != 0) continue;
    const std::string cell = line.substr(2, line.find(" |", 2) - 2);
    if (cell.find("src/") != std::string::npos) cells.push_back(cell);  // not the header row
  }
  return cells;
}

/// The text with comments, string and character literals blanked (newlines kept).
std::string code(const std::string& text) {
  std::string out = text;
  size_t i = 0;
  auto blank = [&](size_t from, size_t to) {
    for (size_t k = from; k < to && k < out.size(); ++k)
      if (out[k] != '\n') out[k] = ' ';
  };
  while (i < text.size()) {
    if (text.compare(i, 2, "//") == 0) {
      const size_t end = std::min(text.find('\n', i), text.size());
      blank(i, end);
      i = end;
    } else if (text.compare(i, 2, "/*") == 0) {
      const size_t end = std::min(text.find("*/", i + 2), text.size() - 2) + 2;
      blank(i, end);
      i = end;
    } else if (text[i] == '"' ||
               (text[i] == '\'' && !(i > 0 && std::isxdigit(static_cast<unsigned char>(text[i - 1]))))) {
      // A literal (a ' after a hex digit is a digit separator: 200'000).
      size_t k = i + 1;
      while (k < text.size() && text[k] != text[i]) k += text[k] == '\\' ? 2 : 1;
      blank(i + 1, k);
      i = k + 1;
    } else {
      ++i;
    }
  }
  return out;
}

struct Function {
  std::string name;
  size_t first_line, lines;
};

/// Function bodies outside other function bodies: a '{' after a parameter list (and
/// qualifiers), not after if/for/while/switch/catch. Lambdas inside functions count with them.
std::vector<Function> functionsOf(const std::string& text) {
  const std::string c = code(text);
  std::vector<Function> functions;
  struct Open {
    bool function;
    size_t at;
    std::string name;
  };
  std::vector<Open> open;
  auto lineAt = [&](size_t at) { return static_cast<size_t>(std::count(c.begin(), c.begin() + at, '\n')) + 1; };
  for (size_t i = 0; i < c.size(); ++i) {
    if (c[i] == '}') {
      if (open.empty()) continue;
      const Open o = open.back();
      open.pop_back();
      if (o.function) functions.push_back({o.name, lineAt(o.at), lineAt(i) - lineAt(o.at) + 1});
      continue;
    }
    if (c[i] != '{') continue;
    const bool in_function = std::any_of(open.begin(), open.end(), [](const Open& o) { return o.function; });
    // Back over qualifiers to the ')' that ends a parameter list.
    size_t k = i;
    while (k > 0) {
      while (k > 0 && std::isspace(static_cast<unsigned char>(c[k - 1]))) --k;
      size_t word = k;
      while (word > 0 && (std::isalnum(static_cast<unsigned char>(c[word - 1])) || c[word - 1] == '_')) --word;
      const std::string w = c.substr(word, k - word);
      if (w == "const" || w == "noexcept" || w == "override" || w == "final" || w == "mutable") {
        k = word;
        continue;
      }
      break;
    }
    bool function = !in_function && k > 0 && c[k - 1] == ')';
    std::string name;
    if (function) {
      int depth = 0;  // to the matching '('
      size_t p = k - 1;
      for (;; --p) {
        if (c[p] == ')') ++depth;
        if (c[p] == '(' && --depth == 0) break;
        if (p == 0) break;
      }
      size_t end = p;
      while (end > 0 && std::isspace(static_cast<unsigned char>(c[end - 1]))) --end;
      size_t begin = end;
      while (begin > 0 && (std::isalnum(static_cast<unsigned char>(c[begin - 1])) || c[begin - 1] == '_' ||
                           c[begin - 1] == ':' || c[begin - 1] == '~'))
        --begin;
      name = c.substr(begin, end - begin);
      if (name == "if" || name == "for" || name == "while" || name == "switch" || name == "catch" || name.empty() ||
          c[begin > 0 ? begin - 1 : 0] == ']')
        function = false;
      else
        open.push_back({true, p, name});
    }
    if (!function) open.push_back({false, i, ""});
  }
  return functions;
}

TEST(Layout, NoSourceFileOver600LinesUnlessListedWithItsReason) {
  const std::vector<std::string> listed = listedIn("## Files over ~600 lines");
  ASSERT_FALSE(listed.empty()) << "docs/architecture.md has no table of long files";
  size_t files = 0;
  for (const fs::path& file : sourceFiles()) {
    ++files;
    const std::string text = slurp(file);
    const size_t lines = static_cast<size_t>(std::count(text.begin(), text.end(), '\n'));
    const std::string path = repoPath(file);
    const bool is_listed = std::find(listed.begin(), listed.end(), path) != listed.end();
    if (lines > kMaxFileLines) {
      EXPECT_TRUE(is_listed) << path << " has " << lines << " lines: split it by job, or list it with the reason in "
                             << "docs/architecture.md's \"Files over ~600 lines\"";
    }
  }
  EXPECT_GT(files, 100u);
  for (const std::string& path : listed)
    EXPECT_TRUE(fs::exists(fs::path(STRIKE_SOURCE_DIR) / path))
        << "docs/architecture.md lists " << path << ", which is not there";
}

TEST(Layout, NoFunctionOver120LinesUnlessListedWithItsReason) {
  const std::vector<std::string> listed = listedIn("## Functions over ~120 lines");
  ASSERT_FALSE(listed.empty()) << "docs/architecture.md has no table of long functions";
  // A row names its functions in backquotes with their file in brackets, or a folder
  // ("src/transfer: ...") whose owner splits them.
  auto isListed = [&](const std::string& name, const std::string& path) {
    for (const std::string& row : listed) {
      if (row.find("`" + name + "`") != std::string::npos && row.find(path) != std::string::npos) return true;
      const size_t colon = row.find(':');
      if (colon != std::string::npos && row.rfind("src/", 0) == 0 && path.rfind(row.substr(0, colon) + "/", 0) == 0)
        return true;
    }
    return false;
  };
  size_t functions = 0;
  for (const fs::path& file : sourceFiles()) {
    const std::string path = repoPath(file);
    for (const Function& f : functionsOf(slurp(file))) {
      ++functions;
      if (f.lines > kMaxFunctionLines) {
        EXPECT_TRUE(isListed(f.name, path))
            << path << ":" << f.first_line << ": " << f.name << " has " << f.lines << " lines: split it into named "
            << "steps, or list it with the reason in docs/architecture.md's \"Functions over ~120 lines\"";
      }
    }
  }
  EXPECT_GT(functions, 500u);
}

TEST(Layout, TheFunctionCounterFindsFunctionsAndTheirLengths) {
  // The counter itself, on a small text: a namespace, a struct with a member function, a
  // function with a lambda, a string with braces, a comment with braces, a digit separator.
  const std::string text =
      "namespace a {\n"              // 1
      "struct S {\n"                 // 2
      "  int f() const {\n"          // 3
      "    return 1;\n"              // 4
      "  }\n"                        // 5
      "};\n"                         // 6
      "int g(int x) {\n"             // 7
      "  auto h = [](int y) {\n"     // 8
      "    return y;  // }\n"        // 9
      "  };\n"                       // 10
      "  if (x) { x = 200'000; }\n"  // 11
      "  const char* s = \"{{\";\n"  // 12
      "  return h(x);\n"             // 13
      "}\n"                          // 14
      "}  // namespace a\n";         // 15
  const std::vector<Function> f = functionsOf(text);
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[0].name, "f");
  EXPECT_EQ(f[0].first_line, 3u);
  EXPECT_EQ(f[0].lines, 3u);
  EXPECT_EQ(f[1].name, "g");
  EXPECT_EQ(f[1].first_line, 7u);
  EXPECT_EQ(f[1].lines, 8u);
}

}  // namespace
}  // namespace strike
