// The CSV reader against the reader it replaced (tests/support/csv_reference.hpp: getline, a
// string per field, strtod): on every input, the same rows bit for bit, or the same error
// (message, file, line, column, text). And parse_csv_number against the strtod version on the
// spellings strtod accepts and std::from_chars does not.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "support/csv_reference.hpp"
#include "usv_fdi/io/csv.hpp"

namespace usvfdi::io {
namespace {

/// Bit pattern of a double, with every NaN alike (a NaN is a missing value).
std::uint64_t bits(double x) {
  if (std::isnan(x)) return 0x7ff8000000000000ull;
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

/// Everything a reader showed of one input.
struct Outcome {
  std::vector<std::array<std::uint64_t, 5>> rows;
  std::vector<std::string> header;
  std::vector<std::size_t> lines;  ///< line() after each row
  bool failed = false;
  std::string what, file, column, text;
  std::size_t line = 0;
  std::size_t rows_count = 0;
};

template <typename Reader>
Outcome read_with(const std::string& input) {
  Outcome o;
  std::unique_ptr<Reader> r;
  try {
    r = std::make_unique<Reader>(std::make_unique<std::istringstream>(input), "eq.csv");
    o.header = r->header();
    Sample s;
    while (r->next(&s)) {
      o.rows.push_back({bits(s.t), bits(s.v), bits(s.r), bits(s.delta), bits(s.u)});
      o.lines.push_back(r->line());
    }
  } catch (const InputError& e) {
    o.failed = true;
    o.what = e.what();
    o.file = e.file();
    o.line = e.line();
    o.column = e.column();
    o.text = e.text();
  }
  if (r) o.rows_count = r->rows();
  return o;
}

std::string printable(const std::string& s) {
  std::string p;
  for (const char c : s.substr(0, 400)) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f) {
      p += c;
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      p += hex;
    }
  }
  return p;
}

void expect_same(const std::string& input) {
  const Outcome want = read_with<reference::CsvSampleReader>(input);
  const Outcome got = read_with<CsvSampleReader>(input);
  SCOPED_TRACE("input: " + printable(input));
  EXPECT_EQ(got.failed, want.failed) << got.what << " | " << want.what;
  EXPECT_EQ(got.what, want.what);
  EXPECT_EQ(got.file, want.file);
  EXPECT_EQ(got.line, want.line);
  EXPECT_EQ(got.column, want.column);
  EXPECT_EQ(got.text, want.text);
  EXPECT_EQ(got.header, want.header);
  EXPECT_EQ(got.rows, want.rows);
  EXPECT_EQ(got.lines, want.lines);
  EXPECT_EQ(got.rows_count, want.rows_count);
}

TEST(CsvEquivalence, ParseNumberAcceptsWhatStrtodAccepted) {
  // strtod's spellings that std::from_chars refuses or reads otherwise, and their neighbours.
  const char* fields[] = {
      "0",
      "-0",
      "+0",
      "+1",
      " +2.5 ",
      "\t-3e2\t",
      "1.",
      ".5",
      "-.5",
      "+.5e-1",
      "1e5",
      "1E+05",
      "1e",
      "1e+",
      "1e-",
      "e5",
      ".",
      "+",
      "-",
      "+-1",
      "--1",
      "1..2",
      "1.2.3",
      "0x1p3",
      "0X1.8P1",
      "-0x10",
      "0x",
      "0x.",
      "0xg",
      "0x1p",
      "0x1p+",
      "0x1.p-2",
      "0x.8",
      "+0x1",
      "0x1e3",
      "inf",
      "-inf",
      "+inf",
      "INF",
      "Infinity",
      "-INFINITY",
      "infinit",
      "infinityx",
      "nan",
      "NaN",
      "NAN",
      "nAn",
      "-nan",
      "+nan",
      "nan()",
      "nan(123)",
      "NaN(abc_9)",
      "nan(",
      "nan(1",
      "nan)",
      "1e400",
      "-1e400",
      "1e-400",
      "4.9e-324",
      "2.2250738585072011e-308",
      "1e-320",
      "",
      " ",
      "\t \t",
      "\v1",
      "\f1",
      "\r1",
      "\n1",
      "1\v",
      "1\r",
      " \v 1",
      "1 2",
      "1,2",
      "1d",
      "1f",
      "0.1x",
      "00012",
      "0b101",
      "1_000",
      "\xEF\xBB\xBF"
      "1",
      "1#",
      "#1",
      "179769313486231580793728971405303415079934132710037826936173778980444968292764750946649"
      "017977587207096330286416692887910946555547851940402630657488671505820681908902000708383"
      "676273854845817711531764475730270069855571366959622842914819860834936475292719074168444"
      "365510704342711559699508093042880177904174497792",
      "0.00000000000000000000000000000000000000000000000000000000000000000000000000000000000001",
      "9007199254740993",
      "0.1000000000000000055511151231257827021181583404541015625",
      "-1.7976931348623157e308",
      "1.7976931348623159e308"};
  for (const char* f : fields) {
    double want = -1.0, got = -1.0;  // left alone on false
    const bool ok_want = reference::parse_csv_number(f, &want);
    const bool ok_got = parse_csv_number(f, &got);
    EXPECT_EQ(ok_got, ok_want) << "field '" << printable(f) << "'";
    EXPECT_EQ(bits(got), bits(want)) << "field '" << printable(f) << "': " << got << " vs " << want;
    EXPECT_EQ(std::signbit(got), std::signbit(want)) << "field '" << printable(f) << "'";
  }
  // A NUL ended strtod's C string: what followed it was never read.
  for (const std::string& f :
       {std::string("1\0x", 3), std::string("1 \0x", 4), std::string("\0x", 2),
        std::string("nan\0", 4), std::string(" 2\0 ", 4), std::string("\0", 1)}) {
    double want = -1.0, got = -1.0;  // left alone on false
    EXPECT_EQ(parse_csv_number(f, &got), reference::parse_csv_number(f, &want))
        << "field '" << printable(f) << "'";
    EXPECT_EQ(bits(got), bits(want)) << "field '" << printable(f) << "'";
  }
}

TEST(CsvEquivalence, ParseNumberSpellings) {
  // The spellings above, with their values spelled out.
  double x = 0.0;
  ASSERT_TRUE(parse_csv_number("+1", &x));
  EXPECT_EQ(x, 1.0);
  ASSERT_TRUE(parse_csv_number("0x1p3", &x));
  EXPECT_EQ(x, 8.0);
  ASSERT_TRUE(parse_csv_number(" -Infinity", &x));
  EXPECT_TRUE(std::isinf(x) && x < 0);
  ASSERT_TRUE(parse_csv_number("1e400", &x));
  EXPECT_TRUE(std::isinf(x));
  ASSERT_TRUE(parse_csv_number("1e-400", &x));
  EXPECT_EQ(x, 0.0);
  ASSERT_TRUE(parse_csv_number("\v7", &x));
  EXPECT_EQ(x, 7.0);
  EXPECT_FALSE(parse_csv_number("0x", &x));
  EXPECT_FALSE(parse_csv_number("1e", &x));
  EXPECT_FALSE(parse_csv_number("infinit", &x));
}

TEST(CsvEquivalence, HandWrittenInputs) {
  const std::string max(kCsvMaxLine, ' ');
  const std::string inputs[] = {
      "",
      "\n",
      "t,v,r,delta",
      "t,v,r,delta\n",
      "t,v,r,delta\n0,0,0,0",
      "t,v,r,delta\n0,0,0,0\n\n\n",
      " t , v ,r,delta,\n1,2,3,4,\n",
      "t,v,r,delta,,\n1,2,3,4,,\n",
      "t,v,r,delta,u\n1,2,3,4,+5\n1,2,3,4, nan \n",
      "t,v,r,delta,u,u\n",
      "t,v,r,delta,x,x\n",
      ",,t,v,r,delta\n",
      "t,v,r\n",
      "v,r,delta\n",
      "t,v,r,delta\n1,2,3\n",
      "t,v,r,delta\n1,2,3,4,5\n",
      "t,v,r,delta\n+1,0x1p3,inf,-nan\n",
      "t,v,r,delta\n 1 , 2 ,\t3\t,4\n",
      "t,v,r,delta\n1,2,3,4 x\n",
      "t,v,r,delta\nx,y,z,w\n",
      "t,v,r,delta\n1,2,3,4\r\n5,6,7,8\r\n",
      "t,v,r,delta\r\n1,2,3,4\r\r\n",
      "t,v,r,delta\r1,2,3,4\r",
      "\r\n",
      "\xEF\xBB\xBFt,v,r,delta\n1,2,3,4\n",
      "\xEF\xBB\xBF\n\xEF\xBB\xBFt,v,r,delta\n",
      "\xEF\xBB\xBF# c\nt,v,r,delta\n1,2,3,4\n",
      "\xEF\xBB\n",
      "# only\n  # comment\n\t\n",
      "t,v,r,delta\n  # comment, with, commas\n1,2,3,4\n#\n",
      std::string("t,v,r,delta\n1,2,\0,4\n", 20),
      std::string("\0t,v,r,delta\n", 13),
      std::string("t,v,r,delta\n# \0 in a comment\n", 29),
      std::string("t,v,r,delta\n1,2,3,4\r\0\n", 22),
      "t,v,r,delta\n0,0,0," + max + "\n",
      "t,v,r,delta\n" + max + "\n",
      "t,v,r,delta\n" + max + "x\n",
      "t,v,r,delta\n" + max + "xy\n",
      "t,v,r,delta\n" + max + "x",
      "t,v,r,delta\n" + max + "xy",
      "t,v,r,delta\n" + max.substr(1) + "\r\n1,2,3,4\n",
      "t,v,r,delta\n" + max + "\r\n1,2,3,4\n",
      "t,v,r,delta\n# " + max + "\n",
      "\xEF\xBB\xBF" + max.substr(3) + "\n",
      "\xEF\xBB\xBF" + max.substr(2) + "\n",
      max + "\n",
      "t,v,r,delta\n1,2,3,4\n" + std::string(3 * kCsvMaxLine, '1'),
  };
  for (const std::string& in : inputs) expect_same(in);
}

TEST(CsvEquivalence, FuzzCorpus) {
  namespace fs = std::filesystem;
  std::size_t n = 0;
  for (const auto& e :
       fs::directory_iterator(std::string(USV_FDI_SOURCE_DIR) + "/tests/fuzz/corpus/csv")) {
    std::ifstream f(e.path(), std::ios::binary);
    expect_same(std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()));
    ++n;
  }
  EXPECT_GT(n, 0u);
}

TEST(CsvEquivalence, RandomEditsOfAValidFile) {
  // Seeded random edits (insert, delete, duplicate, swap bytes) of a small valid file, with
  // the bytes that matter to the reader: separators, line ends, blanks, NUL, BOM, signs...
  const std::string base =
      "\xEF\xBB\xBF# voyage\nt,u,v,r,delta,fault\n0,2.5,0.1,-0.01,0.05,\n"
      "0.02,2.5,nan,1e-3,0.05,bias\r\n\n0.04, 2.4 ,0x1p-3,inf,-0.0,\n# end\n0.06,,+1,2,3,x\n";
  const std::string alphabet =
      std::string(",\n\r\t #+-.eExXpnaifNAI0123456789u\xEF\xBB\xBF") + std::string(1, '\0') + "\v";
  std::mt19937_64 rng(14);
  for (int round = 0; round < 4000; ++round) {
    std::string s = base;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < edits; ++k) {
      const std::size_t at = s.empty() ? 0 : rng() % (s.size() + 1);
      switch (rng() % 4) {
        case 0:
          s.insert(at, 1, alphabet[rng() % alphabet.size()]);
          break;
        case 1:
          if (at < s.size()) s.erase(at, 1 + rng() % 3);
          break;
        case 2:
          if (at < s.size()) s.insert(at, s.substr(at, 1 + rng() % 12));
          break;
        default:
          if (at < s.size()) s[at] = alphabet[rng() % alphabet.size()];
          break;
      }
    }
    expect_same(s);
    if (::testing::Test::HasFailure()) break;  // one input is enough to read
  }
}

TEST(CsvEquivalence, LargeFileAcrossReadBlocks) {
  // Megabytes of rows of every length up to the limit, comments and blank lines, so that
  // lines straddle any block the reader reads in.
  std::mt19937_64 rng(6);
  std::string s = "t,v,r,delta,pad\n";
  while (s.size() < (6u << 20)) {
    switch (rng() % 8) {
      case 0:
        s += "# comment " + std::string(rng() % 200, 'c') + "\n";
        break;
      case 1:
        s += rng() % 2 ? "\n" : "\r\n";
        break;
      case 2:
        s += "1,2,3,4," + std::string(rng() % (kCsvMaxLine - 8), 'p') + "\n";
        break;
      default: {
        char row[160];
        std::snprintf(row, sizeof row, "%.17g,%.17g,%.17g,%.17g,%s\n",
                      static_cast<double>(rng() % 1000000) * 1e-3,
                      std::ldexp(static_cast<double>(rng() % 1000000), -20), -1.0 / (1 + rng() % 7),
                      static_cast<double>(rng()), rng() % 2 ? "x" : "");
        s += row;
      }
    }
  }
  expect_same(s);
  expect_same(s + "1,2,3\n");
  expect_same(s + std::string(kCsvMaxLine + 5, '9'));
}

}  // namespace
}  // namespace usvfdi::io
