#pragma once
// gnuplot for the CLI's charts, run without a shell: the program by its argument vector, the
// script on its standard input, the picture from its standard output into the chart file (by
// rp::OutputFile). No file name ever appears in a script, and text from files (scene names,
// method labels) goes in only through gnuplot_string / gnuplot_label, so nothing a user
// writes can become a gnuplot or shell command. Data travels inside the script as inline
// data blocks, so no temporary data files exist.

#include <string>
#include <string_view>
#include <vector>

namespace rp::cli {

/// The chart formats by the output's extension: ".png" (pngcairo) or ".svg".
enum class ChartFormat { png, svg };

/// The format for `file` by its extension (case-insensitive); rp::Error naming the file and
/// the extension for anything else.
ChartFormat chart_format(const std::string& file);

/// Throws rp::Error with the install hint when no gnuplot is on PATH.
void require_gnuplot();

/// The chart drawn beside `chart`: "<folder>/<stem><suffix><extension>" ("-scaling", "-pareto").
std::string companion_chart(const std::string& chart, const std::string& suffix);

/// Checks, before any work, that plot_to(file, ...) can write `file`: its format, gnuplot on
/// PATH, and an output rp::OutputFile can make (check_output). Throws rp::Error.
void check_chart_output(const std::string& file);

/// `text` as a gnuplot single-quoted string (quotes included): a quote is doubled, control
/// characters become '?'. gnuplot does no substitution of any kind inside single quotes.
std::string gnuplot_string(std::string_view text);

/// `text` for a double-quoted label inside an inline data block: quotes, backslashes and
/// control characters become '?', so a label can neither end its field nor its line.
std::string gnuplot_label(std::string_view text);

/// The point style of series i, the same in every chart: " pt P lc rgb 'C'", a colour and a
/// point type that differ from series to series (the pair repeats only after 130 series), so
/// a legend names each point without labels on the plot.
std::string point_style(size_t i);

/// gnuplot commands that draw, in the multiplot cell at screen fractions (x, y) of size
/// (w, h), nothing but a key: labels[i] beside a point of point_style(i).
std::string legend_cell(const std::vector<std::string>& labels, double x, double y, double w, double h);

/// Draws `file` with gnuplot: `script` (without `set terminal` and `set output`) run after
/// `set terminal <terminal size> noenhanced`, the terminal chosen by the file's extension.
/// gnuplot writes the chart into a pipe and rp::OutputFile writes it to `file`, checking every
/// write. Throws rp::Error with gnuplot's first error line, or the failed write; `file` is
/// then left as it was.
void plot_to(const std::string& file, const std::string& size, const std::string& script);

}  // namespace rp::cli
