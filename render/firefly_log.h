// SPDX-License-Identifier: Apache-2.0
// The firefly log: records the individual sample contributions that make fireflies, with what the
// integrator and the light sampler knew when it made them (docs/fireflies.md uses it to classify them).
//
// A contribution is what one sample adds to its pixel's sum at one path vertex: the light sample's
// beta * f|cos| * Le * w / p_light, or the BSDF sample's beta * f|cos| * Le * w / p_bsdf. Its
// "luminance" is the channel average. Every contribution whose luminance exceeds the pixel's threshold
// is recorded; everything else is untouched, and the log never draws a random number or changes a
// sampler's state, so the image is bit-identical with the log on or off.
//
// Cost when off: RenderOptions::firefly_log is null, the integrator's recorder pointer is null, and the
// only work is a null check per pixel sample and per contribution. When on: a compare per contribution;
// the table look-ups below happen only for recorded samples (rare, if the threshold is sensible).
//
//   FireflyLogOptions log;  log.threshold = 1e3f;             // absolute, per sample
//   RenderOptions o;  o.firefly_log = &log;
//   RenderResult r = render(scene, o);                       // r.fireflies, sorted
//   write_firefly_csv("fireflies.csv", r.fireflies);
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "envpis/envpis.h"
#include "render/math.h"

namespace envpis::render {

class LightSampler;

enum class SampleTechnique { Light, Bsdf };
const char* to_string(SampleTechnique t);  ///< "light" | "bsdf"

struct FireflyLogOptions {
  /// Absolute threshold on a contribution's luminance (> 0), used when pixel_threshold is empty.
  float threshold = 0;
  /// Optional per-pixel thresholds (width * height, row-major, each >= 0); compare's relative mode.
  std::vector<float> pixel_threshold;
  /// At most this many records are kept; later ones are only counted (RenderResult::fireflies_dropped),
  /// so a threshold set too low cannot exhaust memory. Which ones are kept then depends on threading.
  std::size_t max_records = 1000000;
};

/// Throws Error unless the options suit a width x height render.
void validate(const FireflyLogOptions& options, int width, int height);

struct FireflyRecord {
  int x = 0, y = 0;      ///< pixel
  int sample = 0;        ///< sample index in the pixel
  int depth = 0;         ///< path vertex (0: the camera ray's first hit)
  int object = -1;       ///< the object shaded at that vertex (Scene::objects() index)
  SampleTechnique technique = SampleTechnique::Light;
  Rgb contribution;      ///< what the sample added to the pixel sum at this vertex
  float threshold = 0;   ///< the pixel's threshold it exceeded
  float light_pdf = 0;   ///< the strategy's light density of the direction (0: no light samples)
  float bsdf_pdf = 0;    ///< the material's sampling density of the direction
  float mis_weight = 1;  ///< w of this technique (1 without MIS)
  Rgb radiance;          ///< EnvironmentMap::eval of the direction
  Rgb f_cos;             ///< BSDF value times |cos| (for a BSDF sample: its weight times its pdf)
  Rgb beta;              ///< path throughput before this vertex (1 for `direct`)
  Vec3 direction;        ///< world direction of the sample
  // The light table at the direction (cell -1 and the rest 0 when the strategy has no table).
  int cell = -1;                  ///< top cell (ImportanceTable::cell_of_direction)
  int texel_x = -1, texel_y = -1; ///< fine texel of the equal-area square
  float texel_importance = 0;     ///< ImportanceTable::importance of that texel
  float table_pdf = 0;            ///< the table's own (environment-only) density, what mis samples
  float cell_env_probability = 0; ///< E[c]
  float cell_probability = 0;     ///< the strategy's probability of the cell (product: P[c] / sum P)
  float pdf_in_cell = 0;          ///< density of the cell's fine distribution (cell area 1)
  // Product only (0 otherwise): the BSDF proxy at the cell (its cone, what P[c] used) and at the direction.
  float proxy_cell = 0, proxy_direction = 0;
};

/// Sorts by pixel (row-major), sample, depth, technique: the order does not depend on threading.
void sort_records(std::vector<FireflyRecord>& records);

/// Writes the records as CSV with a header row (docs/fireflies.md lists the columns). RGB values are
/// written as channel averages. Throws Error when the file cannot be written.
void write_firefly_csv(const std::string& path, const std::vector<FireflyRecord>& records);

/// What the integrator knows about one contribution; the recorder adds the table's view of it.
struct FireflyEvent {
  SampleTechnique technique = SampleTechnique::Light;
  int depth = 0, object = -1;
  Rgb contribution, radiance, f_cos, beta;
  Vec3 direction;
  float light_pdf = 0, bsdf_pdf = 0, mis_weight = 1;
};

/// One per render thread: knows the current pixel sample and collects its records.
class FireflyRecorder {
 public:
  /// `table`: the strategy's light table (null for bsdf); `kept` is shared by all threads' recorders.
  FireflyRecorder(const FireflyLogOptions& options, int width, const ImportanceTable* table,
                  std::atomic<std::size_t>* kept);
  void begin_sample(int x, int y, int sample);
  /// Whether a contribution of this luminance is recorded (the integrator's only per-contribution test).
  bool exceeds(float luminance) const { return luminance > threshold_; }
  /// Records the event; `light` (prepared for the event's shading point) gives product's proxy.
  void record(const FireflyEvent& event, const LightSampler& light);

  std::vector<FireflyRecord> records;
  std::size_t dropped = 0;

 private:
  void add_table_view(const LightSampler& light, FireflyRecord& r) const;

  const FireflyLogOptions* options_;
  int width_;
  const ImportanceTable* table_;
  std::atomic<std::size_t>* kept_;
  int x_ = 0, y_ = 0, sample_ = 0;
  float threshold_ = 0;
};

}  // namespace envpis::render
