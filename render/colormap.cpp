#include "render/colormap.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

namespace pandora {

namespace {

// 3x5 glyphs, rows top to bottom, '#' set. Letters are drawn as capitals.
const std::map<char, const char*>& Font() {
  static const std::map<char, const char*> kFont{
      {'0', "####.##.##.####"}, {'1', ".#.##..#..#.###"}, {'2', "###..#####..###"},
      {'3', "###..#.##..####"}, {'4', "#.##.####..#..#"}, {'5', "####..###..####"},
      {'6', "####..####.####"}, {'7', "###..#..#.#..#."}, {'8', "####.#####.####"},
      {'9', "####.####..####"}, {'.', ".............#."}, {'-', "......###......"},
      {'+', "....#.###.#...."}, {'/', "..#..#.#.#..#.."}, {'_', "............###"},
      {'%', "#.#..#.#.#..#.#"}, {'=', "...###...###..."}, {'<', "..#.#.#...#...#"},
      {'>', "#...#...#.#.#.."}, {' ', "..............."}, {'a', ".#.#.#####.##.#"},
      {'b', "##.#.###.#.###."}, {'c', ".###..#..#...##"}, {'d', "##.#.##.##.###."},
      {'e', "####..##.#..###"}, {'f', "####..##.#..#.."}, {'g', ".###..#.##.#.##"},
      {'h', "#.##.#####.##.#"}, {'i', "###.#..#..#.###"}, {'j', "..#..#..##.#.#."},
      {'k', "#.##.###.#.##.#"}, {'l', "#..#..#..#..###"}, {'m', "#.########.##.#"},
      {'n', "##.#.##.##.##.#"}, {'o', ".#.#.##.##.#.#."}, {'p', "##.#.###.#..#.."},
      {'q', ".#.#.##.###..##"}, {'r', "##.#.###.#.##.#"}, {'s', ".###...#...###."},
      {'t', "###.#..#..#..#."}, {'u', "#.##.##.##.####"}, {'v', "#.##.##.##.#.#."},
      {'w', "#.##.########.#"}, {'x', "#.##.#.#.#.##.#"}, {'y', "#.##.#.#..#..#."},
      {'z', "###..#.#.#..###"}, {'[', "##.#..#..#..##."}, {']', "##..#..#..#.##."},
      {'(', ".#.#..#..#...#."}, {')', ".#...#..#..#.#."}, {',', "..........#.#.."},
      {':', "....#.....#...."}};
  return kFont;
}

}  // namespace

int TextWidth(const std::string& text, int scale) {
  return text.empty() ? 0 : static_cast<int>(text.size()) * 4 * scale - scale;
}

int DrawText(float* rgb, int width, int height, int x, int y, const std::string& text,
             const Vec3& color, int scale) {
  static const char* kBox = "####.##.##.####";
  int cx = x;
  for (char ch : text) {
    const char lower = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    auto it = Font().find(lower);
    const char* glyph = it == Font().end() ? kBox : it->second;
    const std::string g(glyph);
    for (int row = 0; row < 5; ++row)
      for (int col = 0; col < 3; ++col) {
        const std::size_t k = static_cast<std::size_t>(row * 3 + col);
        if (k >= g.size() || g[k] != '#') continue;
        for (int sy = 0; sy < scale; ++sy)
          for (int sx = 0; sx < scale; ++sx) {
            const int px = cx + col * scale + sx, py = y + row * scale + sy;
            if (px < 0 || py < 0 || px >= width || py >= height) continue;
            float* p = rgb + 3 * (static_cast<std::size_t>(py) * width + px);
            p[0] = static_cast<float>(color.x());
            p[1] = static_cast<float>(color.y());
            p[2] = static_cast<float>(color.z());
          }
      }
    cx += 4 * scale;
  }
  return cx - x;
}

}  // namespace pandora
