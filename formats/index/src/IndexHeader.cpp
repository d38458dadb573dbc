#include "tetrapage/formats/index/IndexHeader.h"

#include <cstdio>

namespace tetrapage {

std::string storage_statement(std::string_view precision, double max_rounding_distance) {
  if (precision != "float")
    return "coordinates stored as read (precision " + std::string(precision) +
           "): answers are exact for the input";
  char line[256];
  std::snprintf(line, sizeof line,
                "coordinates rounded to floats (precision float) by up to %.3g: answers are exact for the "
                "rounded model, not the input",
                max_rounding_distance);
  return line;
}

}  // namespace tetrapage
