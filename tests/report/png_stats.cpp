// png_stats FILE.png: prints "width height distinct_colours non_white_fraction" of a PNG (the
// browser test's check that a screenshot is not blank). libpng's simplified API decodes to RGBA.
#include <png.h>

#include <cstdio>
#include <set>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: png_stats FILE.png\n");
    return 2;
  }
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, argv[1])) {
    std::fprintf(stderr, "png_stats: %s: %s\n", argv[1], image.message);
    return 1;
  }
  image.format = PNG_FORMAT_RGBA;
  std::vector<png_byte> buf(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, buf.data(), 0, nullptr)) {
    std::fprintf(stderr, "png_stats: %s: %s\n", argv[1], image.message);
    return 1;
  }
  std::set<unsigned> colours;
  size_t non_white = 0;
  const size_t n = static_cast<size_t>(image.width) * image.height;
  for (size_t i = 0; i < n; ++i) {
    const png_byte* p = &buf[4 * i];
    colours.insert((unsigned(p[0]) << 16) | (unsigned(p[1]) << 8) | p[2]);
    if (p[0] < 250 || p[1] < 250 || p[2] < 250) ++non_white;
  }
  std::printf("%u %u %zu %.6f\n", image.width, image.height, colours.size(), n ? double(non_white) / n : 0.0);
  return 0;
}
