// The report's two renderings and the stage fingerprints.
#include <gtest/gtest.h>

#include "experiments/document.hpp"
#include "experiments/stages.hpp"

namespace lanechange::experiments {
namespace {

TEST(Document, Base64MatchesTheStandardVectors) {
  // RFC 4648, section 10.
  EXPECT_EQ(base64(""), "");
  EXPECT_EQ(base64("f"), "Zg==");
  EXPECT_EQ(base64("fo"), "Zm8=");
  EXPECT_EQ(base64("foo"), "Zm9v");
  EXPECT_EQ(base64("foob"), "Zm9vYg==");
  EXPECT_EQ(base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64("foobar"), "Zm9vYmFy");
}

TEST(Document, MarkdownAndHtmlHoldTheSameTableAndEscapeText) {
  Document d;
  d.heading(2, "Table <II>");
  d.table({{"planner", "success"}, {{"miqp", "50.0%"}, {"a & b", "`x`"}}});
  d.figure("figures/none.png", "a missing picture");
  const std::string md = d.markdown();
  EXPECT_NE(md.find("## Table <II>"), std::string::npos);
  EXPECT_NE(md.find("| miqp | 50.0% |"), std::string::npos);
  const std::string html = d.html("/nonexistent", "t");
  EXPECT_NE(html.find("<h2>Table &lt;II&gt;</h2>"), std::string::npos);
  EXPECT_NE(html.find("<td>a &amp; b</td><td><code>x</code></td>"), std::string::npos);
  EXPECT_NE(html.find("missing picture: figures/none.png"), std::string::npos);
}

TEST(Stages, FingerprintsDifferWithTheirInputAndAreStable) {
  EXPECT_EQ(fingerprint("abc"), fingerprint("abc"));
  EXPECT_NE(fingerprint("abc"), fingerprint("abd"));
  EXPECT_EQ(fingerprint("").size(), 16U);
  EXPECT_EQ(fingerprint(""), "cbf29ce484222325");  // FNV-1a's offset basis
}

}  // namespace
}  // namespace lanechange::experiments
