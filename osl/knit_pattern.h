/* The pattern knit_fabric.osl compiles with on its own: a 2 x 2 stockinette
 * of one colour. The generator (addon/knitshade_blender/core/shader.py)
 * replaces the line that includes this file with the material's pattern, in
 * the same form: the size (the cell count as a literal too: OSL sizes arrays
 * by integer literals only), whether slip stitches occur, and the stitch codes
 * and colour indices row by row, row 0 the top row as written. */
#define KNIT_PATTERN_ROWS 2
#define KNIT_PATTERN_COLS 2
#define KNIT_PATTERN_CELLS 4
#define KNIT_PATTERN_HAS_FLOATS 0
#define KNIT_PATTERN_CODES { 0, 0, 0, 0 }
#define KNIT_PATTERN_COLOURS { 0, 0, 0, 0 }
